#pragma once
// What every file reader promises, checked on each fuzz input: the call returns, or throws a
// FileError whose message is one printable line. Any other exception escapes and is a finding.
#include <cstdlib>
#include <cstdio>
#include <string>

#include "core/capture.h"
#include "protocol/file_error.h"

namespace skinstream::fuzz {

inline void expect_one_printable_line(const std::string& message) {
  for (const char c : message) {
    if (c < 0x20 || c == 0x7f) {
      std::fprintf(stderr, "message is not one printable line: %s\n", message.c_str());
      std::abort();
    }
  }
}

template <typename Read>
void expect_result_or_file_error(Read&& read) {
  try {
    read();
  } catch (const FileError& e) {
    expect_one_printable_line(e.what());
  }
}

// A capture read must also be consistent: one position per frame and point.
template <typename Read>
void expect_capture_or_file_error(Read&& read) {
  expect_result_or_file_error([&] {
    const Capture c = read();
    if (c.positions.size() != static_cast<size_t>(c.frame_count) * static_cast<size_t>(c.point_count())) std::abort();
  });
}

}  // namespace skinstream::fuzz
