#pragma once
// A golden fixture under tests/protocol/fixtures/ as bytes (empty, with a test failure, when it
// is missing).
#include <gtest/gtest.h>

#include <span>
#include <string>
#include <vector>

#include "support/test_data.h"

namespace skinstream::test {

using ByteVector = std::vector<unsigned char>;

inline ByteVector fixture_bytes(const std::string& relative) {
  const std::string bytes = read_bytes(source_path("tests/protocol/fixtures/" + relative));
  EXPECT_FALSE(bytes.empty()) << "missing fixture " << relative;
  return {bytes.begin(), bytes.end()};
}

inline ByteVector bytes_of(std::span<const unsigned char> s) { return {s.begin(), s.end()}; }

}  // namespace skinstream::test
