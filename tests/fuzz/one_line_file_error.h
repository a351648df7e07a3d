#pragma once
// What every reader promises, checked on each fuzz input: a refusal is one printable line.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/capture.h"

namespace skinstream::fuzz {

inline void expect_one_printable_line(const std::string& message) {
  for (const char c : message) {
    if (c < 0x20 || c == 0x7f) {
      std::fprintf(stderr, "message is not one printable line: %s\n", message.c_str());
      std::abort();
    }
  }
}

// A capture read must be consistent: one position per frame and point.
inline void expect_consistent(const Capture& c) {
  if (c.positions.size() != static_cast<size_t>(c.frame_count) * static_cast<size_t>(c.point_count())) std::abort();
}

}  // namespace skinstream::fuzz
