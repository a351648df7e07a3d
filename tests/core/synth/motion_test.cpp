#include "core/synth/motion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/synth/mannequin.h"

namespace skinstream::synth {
namespace {

struct MotionFixture {
  Body body = make_mannequin();
  Anatomy anatomy = Anatomy::from(body);
};
const MotionFixture& motion_fx() {
  static const MotionFixture f;
  return f;
}

double lowest_sole(const MotionSample& s) {
  const BoneTransforms b = pose_bones(motion_fx().body.skeleton, s.pose);
  double z = 1e18;
  for (Side side : {kLeft, kRight})
    for (const Vec3& p : motion_fx().anatomy.sole_points[side])
      z = std::min(z, (b[static_cast<size_t>(motion_fx().anatomy.leg[side].ankle)] * p).z());
  return z;
}

TEST(SynthMotion, UnknownMotionAndMissingBonesAreRejected) {
  EXPECT_FALSE(is_motion("moonwalk"));
  EXPECT_THROW(motion_angles("moonwalk", motion_fx().anatomy, 0.0, 1.0), std::invalid_argument);
  Body headless;
  headless.skeleton = Skeleton({{"root", -1, Vec3::Zero(), Vec3::UnitZ()}});
  EXPECT_THROW(Anatomy::from(headless), std::invalid_argument);
  EXPECT_THROW(interpolate_keys({}, 0.0, false), std::invalid_argument);
}

TEST(SynthMotion, EveryMotionStartsInTheRestPoseOnTheFloor) {
  for (const std::string& name : motion_names()) {
    const MotionSample s = sample_motion(name, motion_fx().body.skeleton, motion_fx().anatomy, 0.0, 5.0);
    for (const auto& q : s.pose.local)
      EXPECT_LT(q.angularDistance(Eigen::Quaterniond::Identity()), 1e-9) << name;
    EXPECT_TRUE(s.pose.root.linear().isApprox(Eigen::Matrix3d::Identity())) << name;
    EXPECT_NEAR(lowest_sole(s), 0.0, 1e-6) << name;
  }
}

TEST(SynthMotion, MotionsAreSmoothAtCaptureRateAndStayOnTheFloor) {
  const double dt = 1.0 / 120.0;
  for (const std::string& name : motion_names()) {
    double max_step = 0.0, max_clearance = 0.0, min_clearance = 1e18;
    MotionSample prev = sample_motion(name, motion_fx().body.skeleton, motion_fx().anatomy, 0.0, 6.0);
    for (int f = 1; f < 720; ++f) {
      const MotionSample s = sample_motion(name, motion_fx().body.skeleton, motion_fx().anatomy, f * dt, 6.0);
      for (size_t b = 0; b < s.pose.local.size(); ++b)
        max_step = std::max(max_step, s.pose.local[b].angularDistance(prev.pose.local[b]));
      const double c = lowest_sole(s);
      max_clearance = std::max(max_clearance, c);
      min_clearance = std::min(min_clearance, c);
      EXPECT_GE(s.breath, 0.0);
      EXPECT_LE(s.breath, 1.0);
      prev = s;
    }
    EXPECT_LT(max_step, 0.3) << name;  // no jumps: < 17 degrees per frame (a jab peaks near 14)
    EXPECT_NEAR(min_clearance, 0.0, 1e-6) << name;
    if (name == "jumprope" || name == "medley")
      EXPECT_GT(max_clearance, 50.0) << name;  // it really leaves the ground (the medley has a jump rope piece)
    else
      EXPECT_LT(max_clearance, 1e-6) << name;
  }
}

TEST(SynthMotion, RangeOfMotionRaisesTheArmsOverheadAndCrouches) {
  const Skeleton& sk = motion_fx().body.skeleton;
  double max_hand = 0.0, min_hip = 1e18;
  for (int f = 0; f < 20 * 30; ++f) {
    const MotionSample s = sample_motion("rom", sk, motion_fx().anatomy, f / 30.0, 20.0);
    const BoneTransforms b = pose_bones(sk, s.pose);
    max_hand = std::max(
        max_hand,
        (b[static_cast<size_t>(motion_fx().anatomy.arm[kLeft].wrist)] * motion_fx().anatomy.wrist_joint[kLeft]).z());
    min_hip = std::min(
        min_hip, (b[static_cast<size_t>(motion_fx().anatomy.leg[kLeft].hip)] * motion_fx().anatomy.hip_joint[kLeft]).z());
  }
  EXPECT_GT(max_hand, motion_fx().anatomy.shoulder_joint[kLeft].z() + 300.0);  // hands well above the shoulders
  EXPECT_LT(min_hip, motion_fx().anatomy.hip_joint[kLeft].z() - 250.0);        // deep crouch
}

TEST(SynthMotion, PoseBuilderSpeaksAnatomy) {
  const Skeleton& sk = motion_fx().body.skeleton;
  const Anatomy& a = motion_fx().anatomy;
  auto wrist_of = [&](const Pose& p, Side s) {
    return (pose_bones(sk, p)[static_cast<size_t>(a.arm[s].wrist)] * a.wrist_joint[s]).eval();
  };
  PoseBuilder flexed(sk, a);
  flexed.elbow(kLeft, 120.0);  // forearm comes up toward the shoulder
  EXPECT_LT((wrist_of(flexed.pose(), kLeft) - a.shoulder_joint[kLeft]).norm(),
            (a.wrist_joint[kLeft] - a.shoulder_joint[kLeft]).norm() - 100.0);
  PoseBuilder raised(sk, a);
  raised.shoulder(kRight, 90.0, 90.0);  // arm straight forward
  const Vec3 d =
      (pose_bones(sk, raised.pose())[static_cast<size_t>(a.arm[kRight].elbow)] * a.elbow_joint[kRight] -
       a.shoulder_joint[kRight])
          .normalized();
  EXPECT_GT(d.dot(kAxisForward), 0.99);
  PoseBuilder bent(sk, a);
  bent.knee(kLeft, 90.0);  // shank goes backward
  const Vec3 ankle =
      pose_bones(sk, bent.pose())[static_cast<size_t>(a.leg[kLeft].ankle)] * a.ankle_joint[kLeft];
  EXPECT_LT(ankle.y(), a.knee_joint[kLeft].y() - 150.0);
  // The rest angles reproduce the rest pose.
  const Pose rest = build_pose(sk, a, rest_angles(a));
  for (const auto& q : rest.local) EXPECT_LT(q.angularDistance(Eigen::Quaterniond::Identity()), 1e-9);
}

}  // namespace
}  // namespace skinstream::synth
