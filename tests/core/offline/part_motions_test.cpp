#include "core/offline/part_motions.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "tests/core/offline/offline_test_support.h"

namespace skinstream {
namespace {

constexpr int kMotionFrames = 60;

// Each segment of the articulated limb moves rigidly: fitted to its own markers, its motion
// carries every one of them exactly onto where it is in each frame.
TEST(PartMotions, ARigidSegmentsMotionIsRecoveredExactly) {
  const test::ArticulatedLimb limb = test::make_articulated_limb(2, kMotionFrames);
  const int m = static_cast<int>(limb.reference.size());
  std::vector<std::vector<int>> fitted(3);  // segments 0 and 1, and a part fitted to nothing
  for (int i = 0; i < m; ++i) fitted[limb.segment[i]].push_back(i);
  const std::vector<RigidTransform> motion = fit_part_motions(limb.reference, fitted, limb.positions, kMotionFrames);
  ASSERT_EQ(motion.size(), 3u * kMotionFrames);
  auto at = [&](int p, int f) -> const RigidTransform& { return motion[static_cast<size_t>(p) * kMotionFrames + f]; };
  for (int f = 0; f < kMotionFrames; ++f) {
    for (int p = 0; p < 2; ++p)
      for (int i : fitted[p])
        EXPECT_LT((at(p, f).apply(limb.reference[i]) - limb.positions[static_cast<size_t>(f) * m + i]).norm(), 1e-9);
    EXPECT_TRUE(at(2, f).rotation.isIdentity(0.0));
    EXPECT_TRUE(at(2, f).translation.isZero(0.0));
  }
  // The two segments bend against each other: their motions differ away from the reference pose.
  double apart = 0.0;
  for (int f = 0; f < kMotionFrames; ++f) apart = std::max(apart, (at(0, f).rotation - at(1, f).rotation).norm());
  EXPECT_GT(apart, 0.1);
}

}  // namespace
}  // namespace skinstream
