#pragma once
// Comparing two captures in tests: same labels, frames, rate and missing samples, coordinates
// within `tolerance` mm (0: identical).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "core/capture.h"

namespace skinstream::test {

inline std::vector<bool> missing_mask(const Capture& c) {
  std::vector<bool> mask;
  for (const Vec3& p : c.positions) mask.push_back(!is_present(p));
  return mask;
}

inline void expect_same_capture(const Capture& expected, const Capture& actual, double tolerance = 0.0) {
  EXPECT_EQ(actual.labels, expected.labels);
  EXPECT_EQ(actual.frame_count, expected.frame_count);
  EXPECT_EQ(actual.first_frame, expected.first_frame);
  EXPECT_DOUBLE_EQ(actual.rate_hz, expected.rate_hz);
  ASSERT_EQ(actual.positions.size(), expected.positions.size());
  EXPECT_EQ(missing_mask(actual), missing_mask(expected));
  double worst = 0.0;
  for (size_t i = 0; i < expected.positions.size(); ++i)
    if (is_present(expected.positions[i]) && is_present(actual.positions[i]))
      worst = std::max(worst, (expected.positions[i] - actual.positions[i]).cwiseAbs().maxCoeff());
  EXPECT_LE(worst, tolerance);
}

}  // namespace skinstream::test
