#include "core/offline/part_joints.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "core/offline/marker_part_weights.h"
#include "core/offline/part_segmentation.h"
#include "tests/core/offline/offline_test_support.h"

namespace skinstream {
namespace {

constexpr int kJointFrames = 240;

struct Limb {
  test::ArticulatedLimb limb;
  MarkerPartWeights alpha;
  explicit Limb(int segments) : limb(test::make_articulated_limb(segments, kJointFrames)) {
    const std::vector<int> parts = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, kJointFrames,
                                                                limb.segment, AssignmentKind::PerMarker)
                                       .triangle_part;
    alpha = marker_part_weights(limb.reference, limb.triangles, parts, segments, limb.positions, kJointFrames);
  }
  std::vector<PartJoint> joints(const PartJointOptions& options = {}) const {
    return fit_part_joints(limb.reference, alpha.part_member_offsets, alpha.part_members, limb.positions, kJointFrames, options);
  }
};

// The limb's segments are 200 mm long along z and joint k bends about a fixed axis through
// (0, 0, 200 k) in the reference pose (make_articulated_limb): a hinge, so the centre is only
// pinned down to that axis.
double distance_to_hinge(const Vec3& centre, int k) {
  const Vec3 through(0.0, 0.0, 200.0 * k);
  const Vec3 axis(std::cos(1.1 * k), std::sin(1.1 * k), 0.0);
  const Vec3 off = centre - through;
  return (off - off.dot(axis) * axis).norm();
}

TEST(PartJoints, FindsTheHingesOfAnArticulatedLimb) {
  const Limb l(3);
  const std::vector<PartJoint> joints = l.joints();
  ASSERT_EQ(joints.size(), 2u);  // 0-1 and 1-2; 0-2 bend about two axes, no common point
  for (int k = 0; k < 2; ++k) {
    const PartJoint& j = joints[k];
    EXPECT_EQ(j.first, k);
    EXPECT_EQ(j.second, k + 1);
    EXPECT_LT(distance_to_hinge(j.centre, k + 1), 1.0) << "joint " << k;
    // The centre sits between the parts' closest markers, not somewhere far along the hinge.
    EXPECT_LT((j.centre - Vec3(0.0, 0.0, 200.0 * (k + 1))).norm(), 45.0);
    EXPECT_GT(j.axis.z(), 0.99);  // from the first part towards the second
    EXPECT_LT(j.residual_mm, 0.5);
    EXPECT_GT(j.relative_motion_mm, 20.0);
    EXPECT_GT(j.side(Vec3(0.0, 0.0, 200.0 * (k + 1) + 10.0)), 0.0);
    EXPECT_LT(j.side(Vec3(0.0, 0.0, 200.0 * (k + 1) - 10.0)), 0.0);
  }
}

TEST(PartJoints, PartsWithoutACommonPivotAreNotJointed) {
  Limb l(2);
  // The second segment also slides 60 mm up and down (world z): no point stays shared.
  const size_t m = l.limb.reference.size();
  for (int f = 0; f < kJointFrames; ++f)
    for (size_t i = 0; i < m; ++i)
      if (l.limb.segment[i] == 1) l.limb.positions[f * m + i] += Vec3(0.0, 0.0, 60.0 * std::sin(f / 9.0));
  EXPECT_TRUE(l.joints().empty());
  // Loose enough criteria take it anyway (its relative turn is a hinge; the slide is what fails).
  PartJointOptions loose;
  loose.max_residual_ratio = 1.0;
  EXPECT_EQ(l.joints(loose).size(), 1u);
}

// Two segments of the limb's layout: the first still, the second turning about (0, 0, 200) by
// two angles about x and y. turn_y = 0 makes a hinge; both make a ball joint.
Limb two_segments_turning(double turn_x, double turn_y) {
  Limb l(2);
  const size_t m = l.limb.reference.size();
  const Vec3 pivot(0.0, 0.0, 200.0);
  for (int f = 0; f < kJointFrames; ++f) {
    const double t = f / 60.0;
    const Eigen::Matrix3d turn = (Eigen::AngleAxisd(turn_x * std::sin(1.3 * t), Vec3::UnitX()) *
                                  Eigen::AngleAxisd(turn_y * std::sin(2.1 * t + 1.0), Vec3::UnitY()))
                                     .toRotationMatrix();
    for (size_t i = 0; i < m; ++i) {
      const Vec3& r = l.limb.reference[i];
      l.limb.positions[f * m + i] = l.limb.segment[i] == 0 ? r : Vec3(pivot + turn * (r - pivot));
    }
  }
  const std::vector<int> parts = segmentation_from_assignment(l.limb.reference, l.limb.triangles, l.limb.positions,
                                                              kJointFrames, l.limb.segment, AssignmentKind::PerMarker)
                                     .triangle_part;
  l.alpha = marker_part_weights(l.limb.reference, l.limb.triangles, parts, 2, l.limb.positions, kJointFrames);
  return l;
}

TEST(PartJoints, OnlyHingesCount) {
  const Limb hinge = two_segments_turning(0.9, 0.0), ball = two_segments_turning(0.9, 0.6);
  const std::vector<PartJoint> hinges = hinge.joints();
  ASSERT_EQ(hinges.size(), 1u);
  EXPECT_LT(hinges[0].axis_spread, 1e-9);
  EXPECT_LT(hinges[0].residual_mm, 1e-6);
  EXPECT_TRUE(ball.joints().empty());
  // The ball's centre is as good a pivot; only the spread of its axes rules it out.
  PartJointOptions any_axis;
  any_axis.max_axis_spread = 1.0;
  const std::vector<PartJoint> balls = ball.joints(any_axis);
  ASSERT_EQ(balls.size(), 1u);
  EXPECT_GT(balls[0].axis_spread, 0.05);
  // Within the small pull towards the closest markers (0.1% of the turns' stiffness): 0.11 mm.
  EXPECT_LT((balls[0].centre - Vec3(0.0, 0.0, 200.0)).norm(), 0.5);
}

TEST(PartJoints, RejectsBadInputs) {
  const Limb l(2);
  const auto& limb = l.limb;
  const auto& a = l.alpha;
  EXPECT_THROW(fit_part_joints(limb.reference, a.part_member_offsets, a.part_members, limb.positions, kJointFrames - 1),
               std::invalid_argument);
  PartJointOptions zero;
  zero.max_residual_ratio = 0.0;
  EXPECT_THROW(fit_part_joints(limb.reference, a.part_member_offsets, a.part_members, limb.positions, kJointFrames, zero),
               std::invalid_argument);
  PartJointOptions no_spread;
  no_spread.max_axis_spread = 0.0;
  EXPECT_THROW(fit_part_joints(limb.reference, a.part_member_offsets, a.part_members, limb.positions, kJointFrames, no_spread),
               std::invalid_argument);
  std::vector<PartMember> bad = a.part_members;
  bad[0].marker = static_cast<int>(limb.reference.size());
  EXPECT_THROW(fit_part_joints(limb.reference, a.part_member_offsets, bad, limb.positions, kJointFrames), std::invalid_argument);
  std::vector<Vec3> nan = limb.positions;
  nan[5].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fit_part_joints(limb.reference, a.part_member_offsets, a.part_members, nan, kJointFrames), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
