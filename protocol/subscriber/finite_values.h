#pragma once
// Whether every float of a buffer is finite: what the daemon checks before it encodes a frame,
// and a subscriber before it shows one. A frame's vertex buffer holds ~160,000 floats, so the
// check has no branch per value: a float is infinite or NaN exactly when its exponent bits are all
// ones, and adding one to that field then carries into the sign bit.

#include <cstdint>
#include <cstring>
#include <span>

namespace skinstream {

inline bool all_finite(std::span<const float> values) {
  constexpr uint32_t kExponent = 0x7f800000u, kExponentOne = 0x00800000u, kCarry = 0x80000000u;
  uint32_t lanes[4] = {0, 0, 0, 0};  // independent, so the loop is not one long chain
  const size_t n = values.size();
  size_t i = 0;
  for (; i + 4 <= n; i += 4)
    for (size_t k = 0; k < 4; ++k) {
      uint32_t bits;
      std::memcpy(&bits, &values[i + k], sizeof bits);
      lanes[k] |= (bits & kExponent) + kExponentOne;
    }
  for (; i < n; ++i) {
    uint32_t bits;
    std::memcpy(&bits, &values[i], sizeof bits);
    lanes[0] |= (bits & kExponent) + kExponentOne;
  }
  return ((lanes[0] | lanes[1] | lanes[2] | lanes[3]) & kCarry) == 0;
}

}  // namespace skinstream
