#include "core/synth/deformation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/synth/mannequin.h"
#include "core/synth/motion.h"

namespace skinstream::synth {
namespace {

struct DeformFixture {
  Body body = make_mannequin();
  Anatomy anatomy = Anatomy::from(body);
  DeformationModel model{body, anatomy, DeformOptions{}};
  DeformedSurface surface{body.rest, body.faces, body.weights, model};
};
const DeformFixture& deform_fx() {
  static const DeformFixture f;
  return f;
}

int effect_index(const std::string& name) {
  const auto& names = deform_fx().model.effect_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

// Largest displacement beyond skinning over the vertices, and the mean over those moved > 1 mm
// of how well the displacement follows the posed normal.
struct Moved {
  double max_mm = 0.0;
  Vec3 where = Vec3::Zero();
};
Moved displacement(const Pose& pose, const EffectFrame& effects) {
  const BoneTransforms b = pose_bones(deform_fx().body.skeleton, pose);
  Moved m;
  for (int v = 0; v < deform_fx().surface.vertex_count(); ++v) {
    const double d = deform_fx().surface.effect_magnitude(v, b, effects);
    if (d > m.max_mm) {
      m.max_mm = d;
      m.where = deform_fx().body.rest[static_cast<size_t>(v)];
    }
  }
  return m;
}

TEST(SynthDeformation, RejectsMismatchedInputs) {
  const Pose rest = Pose::rest(deform_fx().body.skeleton);
  EXPECT_THROW(deform_fx().model.drive({rest}, {}, {0.0}, {0.0}, 120.0), std::invalid_argument);
  EXPECT_THROW(simulate_jiggle(standard_jiggle(deform_fx().body, deform_fx().anatomy), {}, 0.0), std::invalid_argument);
  EXPECT_THROW(DeformedSurface(deform_fx().body.rest, deform_fx().body.faces, SkinWeights{}, deform_fx().model),
               std::invalid_argument);
}

TEST(SynthDeformation, RegionWeightFollowsFacingMaskAndDistance) {
  Region r;
  r.centre = Vec3(0, 0, 0);
  r.sigma_along = 10.0;
  r.facing = Vec3::UnitY();
  r.mask_bones = {0};
  EXPECT_NEAR(r.weight(Vec3::Zero(), Vec3::UnitY(), 1.0), 1.0, 1e-12);
  EXPECT_EQ(r.weight(Vec3::Zero(), -Vec3::UnitY(), 1.0), 0.0);  // faces away
  EXPECT_EQ(r.weight(Vec3::Zero(), Vec3::UnitY(), 0.0), 0.0);   // masked out
  EXPECT_NEAR(r.weight(Vec3(0, 0, 10), Vec3::UnitY(), 1.0), std::exp(-0.5), 1e-12);
}

TEST(SynthDeformation, BicepsBulgesWithElbowFlexionAndEffort) {
  const Muscle* biceps = nullptr;
  for (const Muscle& m : deform_fx().model.muscles())
    if (m.name == "biceps_L") biceps = &m;
  ASSERT_NE(biceps, nullptr);
  double previous = -1.0;
  for (double flex : {0.0, 40.0, 80.0, 120.0, 140.0}) {
    PoseBuilder b(deform_fx().body.skeleton, deform_fx().anatomy);
    b.elbow(kLeft, flex);
    const double a = muscle_activation(*biceps, b.pose());
    EXPECT_GE(a, previous) << flex;
    previous = a;
  }
  EXPECT_GT(previous, 0.95);
  PoseBuilder straight(deform_fx().body.skeleton, deform_fx().anatomy);
  straight.elbow(kLeft, 0.0);
  EXPECT_LT(muscle_activation(*biceps, straight.pose()), 0.01);
  PoseBuilder flexed(deform_fx().body.skeleton, deform_fx().anatomy);
  flexed.elbow(kLeft, 130.0);
  EXPECT_GT(muscle_bulge_mm(*biceps, flexed.pose(), 1.0), muscle_bulge_mm(*biceps, flexed.pose(), 0.0) + 5.0);

  // On the surface: the front of the left upper arm moves out by about the bulge.
  EffectFrame effects(static_cast<size_t>(deform_fx().model.effect_count()));
  effects[static_cast<size_t>(effect_index("muscle:biceps_L"))].normal_mm =
      muscle_bulge_mm(*biceps, flexed.pose(), 1.0);
  const Moved m = displacement(flexed.pose(), effects);
  EXPECT_GT(m.max_mm, 0.8 * muscle_bulge_mm(*biceps, flexed.pose(), 1.0));
  const Vec3 mid = 0.5 * (deform_fx().anatomy.shoulder_joint[kLeft] + deform_fx().anatomy.elbow_joint[kLeft]);
  EXPECT_LT((m.where - mid).norm(), 120.0);  // on the upper arm
}

TEST(SynthDeformation, BreathingMovesTheBellyOut) {
  std::vector<Pose> poses(2, Pose::rest(deform_fx().body.skeleton));
  std::vector<BoneTransforms> bones(2, pose_bones(deform_fx().body.skeleton, poses[0]));
  const auto frames = deform_fx().model.drive(poses, bones, {0.0, 1.0}, {0.0, 0.0}, 120.0);
  EXPECT_LT(displacement(poses[0], frames[0]).max_mm, 1e-9);
  const Moved m = displacement(poses[1], frames[1]);
  EXPECT_GT(m.max_mm, 12.0);
  EXPECT_GT(m.where.y(), 40.0);  // on the front of the trunk
  EXPECT_GT(m.where.z(), deform_fx().anatomy.hip_joint[kLeft].z());
  EXPECT_LT(m.where.z(), deform_fx().anatomy.shoulder_joint[kLeft].z());
}

TEST(SynthDeformation, SoftTissueLagsOvershootsAndSettles) {
  JiggleRegion r;
  r.name = "blob";
  r.anchor_bone = 0;
  r.anchor_point = Vec3::Zero();
  r.frequency_hz = 4.0;
  r.damping_ratio = 0.15;
  r.gain = 1.0;
  r.max_mm = 1000.0;
  // The bone accelerates upward for 0.25 s, then moves at constant speed.
  const double rate = 120.0;
  std::vector<BoneTransforms> frames;
  for (int f = 0; f < 480; ++f) {
    const double t = f / rate, ta = std::min(t, 0.25);
    const double z = 0.5 * 2000.0 * ta * ta + 2000.0 * 0.25 * std::max(0.0, t - 0.25);  // 2 m/s^2
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.translation() = Vec3(0, 0, z);
    frames.push_back({m});
  }
  const auto u = simulate_jiggle({r}, frames, rate)[0];
  EXPECT_EQ(u[0], Vec3::Zero());
  EXPECT_LT(u[24].z(), -0.5 * 2000.0 / std::pow(2 * M_PI * 4.0, 2));  // lags behind while accelerating
  double overshoot = 0.0;
  for (int f = 30; f < 90; ++f) overshoot = std::max(overshoot, u[static_cast<size_t>(f)].z());
  EXPECT_GT(overshoot, 0.5);                               // then swings past
  EXPECT_LT(u.back().norm(), 0.05 * std::abs(u[24].z()));  // and rings down
  EXPECT_NEAR(u[100].x(), 0.0, 1e-12);                     // only along the acceleration
  // A body at rest does not jiggle.
  const std::vector<BoneTransforms> still(100, BoneTransforms{Eigen::Isometry3d::Identity()});
  const auto resting = simulate_jiggle({r}, still, rate);
  for (const Vec3& v : resting[0]) EXPECT_EQ(v, Vec3::Zero());
}

TEST(SynthDeformation, ZeroScalesMeanSkinningOnly) {
  const DeformationModel off(deform_fx().body, deform_fx().anatomy, DeformOptions{0.0, 0.0, 0.0});
  std::vector<Pose> poses;
  std::vector<BoneTransforms> bones;
  for (int f = 0; f < 60; ++f) {
    poses.push_back(sample_motion("jumprope", deform_fx().body.skeleton, deform_fx().anatomy, f / 120.0, 1.0).pose);
    bones.push_back(pose_bones(deform_fx().body.skeleton, poses.back()));
  }
  const auto frames =
      off.drive(poses, bones, std::vector<double>(60, 1.0), std::vector<double>(60, 1.0), 120.0);
  for (const auto& fr : frames)
    for (const EffectValue& e : fr) {
      EXPECT_EQ(e.normal_mm, 0.0);
      EXPECT_EQ(e.offset_mm, Vec3::Zero());
    }
}

}  // namespace
}  // namespace skinstream::synth
