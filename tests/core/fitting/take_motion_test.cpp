#include "core/fitting/take_motion.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

namespace skinstream {
namespace {

// Ten markers on an upper arm and ten on a forearm 300 mm long; the whole arm turns in space and
// the elbow bends from straight to `elbow_degrees`.
std::vector<Vec3> arm_take(int frame_count, double elbow_degrees) {
  std::vector<Vec3> frames;
  for (int f = 0; f < frame_count; ++f) {
    const double t = static_cast<double>(f) / (frame_count - 1);
    const Eigen::Matrix3d whole = Eigen::AngleAxisd(2.0 * t, Vec3(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
    const Eigen::Matrix3d elbow = Eigen::AngleAxisd(elbow_degrees * M_PI / 180.0 * t, Vec3::UnitY()).toRotationMatrix();
    for (int i = 0; i < 10; ++i) frames.push_back(whole * Vec3(-30.0 * i, 40.0 * std::sin(i), 40.0 * std::cos(i)) + Vec3(0, 0, 1200));
    for (int i = 0; i < 10; ++i)
      frames.push_back(whole * elbow * Vec3(30.0 * (i + 1), 35.0 * std::sin(i), 35.0 * std::cos(i)) + Vec3(0, 0, 1200));
  }
  return frames;
}

TEST(TakeMotion, ABendingJointArticulates) {
  const std::vector<Vec3> take = arm_take(200, 120.0);
  const TakeMotion motion = measure_take_motion(take, 200, 20);
  EXPECT_TRUE(motion.ok()) << motion.problem;
  EXPECT_EQ(motion.pairs, 190);
  // Half the pairs cross the elbow; bent 120 degrees, its far markers come 400 mm closer.
  EXPECT_GT(motion.articulation_mm, TakeMotionLimits{}.min_articulation_mm);
}

TEST(TakeMotion, ARigidObjectTurningInSpaceIsRefusedWithItsFigure) {
  std::vector<Vec3> take = arm_take(200, 0.0);
  // One loose marker flapping 200 mm does not make the object a body.
  for (int f = 0; f < 200; ++f) take[static_cast<size_t>(f) * 20 + 3] += Vec3(200.0 * std::sin(0.1 * f), 0, 0);
  const TakeMotion motion = measure_take_motion(take, 200, 20);
  EXPECT_FALSE(motion.ok());
  EXPECT_LT(motion.articulation_mm, 1.0);
  EXPECT_NE(motion.problem.find("barely change"), std::string::npos) << motion.problem;
}

TEST(TakeMotion, MarkersNotSeenAreLeftOut) {
  std::vector<Vec3> take = arm_take(200, 120.0);
  for (int f = 0; f < 200; ++f) take[static_cast<size_t>(f) * 20 + 19] = missing_point();  // never seen
  for (int f = 0; f < 100; ++f) take[static_cast<size_t>(f) * 20 + 12] = missing_point();  // half the take
  const TakeMotion motion = measure_take_motion(take, 200, 20);
  EXPECT_EQ(motion.pairs, 171);
  EXPECT_TRUE(motion.ok()) << motion.problem;
  EXPECT_TRUE(std::isfinite(motion.articulation_mm));
}

}  // namespace
}  // namespace skinstream
