#include "core/body/skeleton.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/body/body.h"
#include "core/body/skinning.h"

namespace skinstream {
namespace {

std::vector<Bone> chain() {
  return {{"root", -1, Vec3(0, 0, 0), Vec3(0, 0, 100)},
          {"upper", 0, Vec3(0, 0, 100), Vec3(0, 0, 300)},
          {"lower", 1, Vec3(0, 0, 300), Vec3(0, 0, 500)}};
}

TEST(SynthSkeleton, RejectsBadHierarchies) {
  std::vector<Bone> b = chain();
  b[1].parent = 2;  // parent after child
  EXPECT_THROW(Skeleton{b}, std::invalid_argument);
  b = chain();
  b[2].name = "upper";
  EXPECT_THROW(Skeleton{b}, std::invalid_argument);
  b = chain();
  b[0].name.clear();
  EXPECT_THROW(Skeleton{b}, std::invalid_argument);
  b = chain();
  b[2].tail.x() = std::nan("");
  EXPECT_THROW(Skeleton{b}, std::invalid_argument);
  const Skeleton ok(chain());
  EXPECT_THROW(ok.require("nope"), std::invalid_argument);
  EXPECT_EQ(ok.find("nope"), -1);
  Pose p = Pose::rest(ok);
  p.local.pop_back();
  EXPECT_THROW(pose_bones(ok, p), std::invalid_argument);
}

TEST(SynthSkeleton, RestPoseIsIdentityAndBonesRotateAboutTheirHead) {
  const Skeleton sk(chain());
  for (const auto& t : pose_bones(sk, Pose::rest(sk))) EXPECT_TRUE(t.isApprox(Eigen::Isometry3d::Identity()));
  Pose p = Pose::rest(sk);
  p.local[1] = rotation(Vec3::UnitX(), M_PI / 2);  // upper swings forward-up about its head
  const BoneTransforms t = pose_bones(sk, p);
  EXPECT_TRUE((t[1] * Vec3(0, 0, 100)).isApprox(Vec3(0, 0, 100)));           // head stays
  EXPECT_TRUE((t[1] * Vec3(0, 0, 300)).isApprox(Vec3(0, -200, 100), 1e-9));  // tail swung
  EXPECT_TRUE((t[2] * Vec3(0, 0, 500)).isApprox(Vec3(0, -400, 100), 1e-9));  // child follows
  EXPECT_TRUE(sk.is_descendant(2, 0));
  EXPECT_FALSE(sk.is_descendant(0, 2));
}

TEST(SynthSkeleton, TwistAngleRecoversTheRotationAboutAnAxis) {
  const Vec3 axis = Vec3(1, 2, 3).normalized();
  for (double a : {-2.5, -0.3, 0.0, 0.7, 3.0}) EXPECT_NEAR(twist_angle(rotation(axis, a), axis), a, 1e-9);
  // A swing about a perpendicular axis has no twist.
  EXPECT_NEAR(twist_angle(rotation(Vec3::UnitX(), 1.0), Vec3::UnitZ()), 0.0, 1e-12);
}

TEST(SynthSkinning, RejectsBadWeightsAndBlendsTransforms) {
  EXPECT_THROW(SkinWeights::from_lists({{}}, 2), std::invalid_argument);           // no weight
  EXPECT_THROW(SkinWeights::from_lists({{{5, 1.0}}}, 2), std::invalid_argument);   // unknown bone
  EXPECT_THROW(SkinWeights::from_lists({{{0, -1.0}}}, 2), std::invalid_argument);  // negative
  const SkinWeights w = SkinWeights::from_lists({{{0, 2.0}, {1, 2.0}, {1, 0.0}}, {{1, 0.3}}}, 2);
  EXPECT_DOUBLE_EQ(w.weight(0, 0), 0.5);
  EXPECT_DOUBLE_EQ(w.weight(0, 1), 0.5);
  EXPECT_DOUBLE_EQ(w.weight(1, 1), 1.0);
  EXPECT_EQ(w.dominant(1), 1);
  BoneTransforms bones(2, Eigen::Isometry3d::Identity());
  bones[1].translation() = Vec3(10, 0, 0);
  const std::vector<Vec3> rest = {Vec3(0, 0, 0), Vec3(1, 1, 1)};
  const std::vector<Vec3> posed = skin(rest, w, bones);
  EXPECT_TRUE(posed[0].isApprox(Vec3(5, 0, 0)));
  EXPECT_TRUE(posed[1].isApprox(Vec3(11, 1, 1)));
  EXPECT_THROW(skin({Vec3::Zero()}, w, bones), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
