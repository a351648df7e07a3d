#pragma once
// Counts heap allocations made by this thread while a CountAllocations is alive, to prove the
// per-frame paths allocate nothing: operator new, and malloc, calloc and realloc called from
// our code (Eigen's blocks), both in allocation_counter.cpp.
#include <cstddef>

namespace skinstream::test {

class CountAllocations {
 public:
  CountAllocations();
  ~CountAllocations();
  size_t count() const;
};

}  // namespace skinstream::test
