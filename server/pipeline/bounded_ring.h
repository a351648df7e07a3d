#pragma once
// A first-in first-out ring of a fixed capacity over preallocated storage: pushing and popping
// never allocate (only reset() does). The caller holds whatever lock guards it and keeps
// push() below capacity and pop() above empty.

#include <cstddef>
#include <vector>

namespace skinstream::server {

template <typename T>
class BoundedRing {
 public:
  explicit BoundedRing(size_t capacity = 0) : items_(capacity) {}

  // Empties the ring and sets its capacity (allocates).
  void reset(size_t capacity) {
    items_.assign(capacity, T{});
    head_ = count_ = 0;
  }
  void push(T item) { items_[(head_ + count_++) % items_.size()] = item; }
  T pop() {
    T item = items_[head_];
    head_ = (head_ + 1) % items_.size();
    --count_;
    return item;
  }

  const T& front() const { return items_[head_]; }  // the oldest; the ring must not be empty
  const T& at(size_t i) const { return items_[(head_ + i) % items_.size()]; }  // i-th oldest, i < size()
  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  bool full() const { return count_ == items_.size(); }

 private:
  std::vector<T> items_;
  size_t head_ = 0, count_ = 0;
};

}  // namespace skinstream::server
