#include "server/constant_time_equal.h"

#include <algorithm>

namespace skinstream::server {

bool constant_time_equal(std::string_view a, std::string_view b) {
  // Every byte of the longer string is read, the shorter padded with zeros; a length that differs
  // is folded into the same accumulator. volatile keeps the compiler from stopping at the first
  // difference.
  const size_t n = std::max(a.size(), b.size());
  volatile unsigned char difference = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    difference = difference | static_cast<unsigned char>(x ^ y);
  }
  return difference == 0;
}

}  // namespace skinstream::server
