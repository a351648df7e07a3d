#include "core/synth/soft_tissue_jiggle.h"

#include <cmath>
#include <stdexcept>

namespace skinstream::synth {

namespace {

Vec3 perpendicular_part(const Vec3& v, const Vec3& axis) {
  const Vec3 p = v - v.dot(axis) * axis;
  return p.norm() > 1e-9 ? Vec3(p.normalized()) : Vec3(Vec3::Zero());
}

Vec3 saturate(const Vec3& u, double max_mm) {
  const double n = u.norm();
  if (n < 1e-12 || max_mm <= 0.0) return Vec3::Zero();
  return u * (max_mm * std::tanh(n / max_mm) / n);
}

}  // namespace

std::vector<JiggleRegion> standard_jiggle(const Body& body, const Anatomy& a) {
  const Skeleton& sk = body.skeleton;
  std::vector<JiggleRegion> out;
  auto bones = [](std::initializer_list<int> list) {
    std::vector<int> v;
    for (int b : list)
      if (b >= 0) v.push_back(b);
    return v;
  };

  JiggleRegion belly;
  belly.name = "belly";
  belly.region.centre = 0.5 * (sk.bone(a.spine[0]).tail + sk.bone(a.spine[2]).head) + 60.0 * kAxisForward;
  belly.region.axis = kAxisUp;
  belly.region.sigma_along = 110.0;
  belly.region.sigma_across = 170.0;
  belly.region.facing = kAxisForward;
  belly.region.facing_power = 0.7;
  belly.region.mask_bones = bones({a.spine[0], a.spine[1], a.spine[2], a.root});
  belly.anchor_bone = a.spine[1];
  belly.anchor_point = belly.region.centre;
  belly.frequency_hz = 3.2;
  belly.damping_ratio = 0.16;
  belly.gain = 0.75;
  belly.max_mm = 20.0;
  out.push_back(belly);

  JiggleRegion chest;
  chest.name = "chest";
  chest.region.centre = sk.bone(a.spine[3]).head +
                        0.3 * (sk.bone(a.spine[3]).tail - sk.bone(a.spine[3]).head) + 80.0 * kAxisForward;
  chest.region.axis = kAxisUp;
  chest.region.sigma_along = 90.0;
  chest.region.facing = kAxisForward;
  chest.region.mask_bones = bones({a.spine[3], sk.find("breast.L"), sk.find("breast.R")});
  chest.anchor_bone = a.spine[3];
  chest.anchor_point = chest.region.centre;
  chest.frequency_hz = 4.5;
  chest.damping_ratio = 0.2;
  chest.gain = 0.5;
  chest.max_mm = 12.0;
  out.push_back(chest);

  for (Side s : {kLeft, kRight}) {
    const std::string suffix = std::string("_") + side_suffix(s);
    const double l = lateral_sign(s);
    const LegBones& leg = a.leg[s];
    const ArmBones& arm = a.arm[s];

    JiggleRegion buttock;
    buttock.name = "buttock" + suffix;
    buttock.region.centre = a.hip_joint[s] - 90.0 * kAxisForward - 40.0 * kAxisUp;
    buttock.region.sigma_along = 90.0;
    buttock.region.sigma_across = 90.0;
    buttock.region.facing = -kAxisForward;
    buttock.region.facing_power = 0.7;
    buttock.region.mask_bones = bones({leg.pelvis, leg.hip, a.root, a.spine[0]});
    buttock.anchor_bone = a.spine[0];
    buttock.anchor_point = buttock.region.centre;
    buttock.frequency_hz = 4.0;
    buttock.damping_ratio = 0.2;
    buttock.gain = 0.7;
    buttock.max_mm = 14.0;
    out.push_back(buttock);

    JiggleRegion thigh;
    thigh.name = "thigh" + suffix;
    thigh.region.centre = a.hip_joint[s] + 0.45 * (a.knee_joint[s] - a.hip_joint[s]);
    thigh.region.axis = a.thigh_dir[s];
    thigh.region.sigma_along = 0.28 * (a.knee_joint[s] - a.hip_joint[s]).norm();
    thigh.region.mask_bones = bones({leg.hip, leg.thigh_twist});
    thigh.anchor_bone = leg.thigh_twist >= 0 ? leg.thigh_twist : leg.hip;
    thigh.anchor_point = thigh.region.centre;
    thigh.frequency_hz = 5.5;
    thigh.damping_ratio = 0.22;
    thigh.gain = 0.5;
    thigh.max_mm = 10.0;
    out.push_back(thigh);

    JiggleRegion calf;
    calf.name = "calf" + suffix;
    calf.region.centre = a.knee_joint[s] + 0.3 * (a.ankle_joint[s] - a.knee_joint[s]);
    calf.region.axis = a.shank_dir[s];
    calf.region.sigma_along = 0.2 * (a.ankle_joint[s] - a.knee_joint[s]).norm();
    calf.region.facing = perpendicular_part(-kAxisForward, a.shank_dir[s]);
    calf.region.facing_power = 0.8;
    calf.region.mask_bones = bones({leg.knee, leg.shank_twist});
    calf.anchor_bone = leg.knee;
    calf.anchor_point = calf.region.centre;
    calf.frequency_hz = 7.0;
    calf.damping_ratio = 0.25;
    calf.gain = 0.4;
    calf.max_mm = 7.0;
    out.push_back(calf);

    JiggleRegion upper_arm;
    upper_arm.name = "upperarm" + suffix;
    upper_arm.region.centre = a.shoulder_joint[s] + 0.5 * (a.elbow_joint[s] - a.shoulder_joint[s]);
    upper_arm.region.axis = a.upperarm_dir[s];
    upper_arm.region.sigma_along = 0.25 * (a.elbow_joint[s] - a.shoulder_joint[s]).norm();
    upper_arm.region.facing = -perpendicular_part(a.forearm_dir[s], a.upperarm_dir[s]);  // back of the arm
    upper_arm.region.facing_power = 0.8;
    upper_arm.region.mask_bones = bones({arm.upperarm, arm.upperarm_twist});
    upper_arm.anchor_bone = arm.upperarm_twist >= 0 ? arm.upperarm_twist : arm.upperarm;
    upper_arm.anchor_point = upper_arm.region.centre;
    upper_arm.frequency_hz = 5.0;
    upper_arm.damping_ratio = 0.2;
    upper_arm.gain = 0.6;
    upper_arm.max_mm = 10.0;
    out.push_back(upper_arm);

    JiggleRegion flank;
    flank.name = "flank" + suffix;
    flank.region.centre = sk.bone(a.spine[1]).head + l * 130.0 * kAxisRight;
    flank.region.axis = kAxisUp;
    flank.region.sigma_along = 90.0;
    flank.region.facing = l * kAxisRight;
    flank.region.facing_power = 1.5;
    flank.region.mask_bones = bones({a.spine[0], a.spine[1], a.spine[2]});
    flank.anchor_bone = a.spine[1];
    flank.anchor_point = flank.region.centre;
    flank.frequency_hz = 4.0;
    flank.damping_ratio = 0.2;
    flank.gain = 0.6;
    flank.max_mm = 10.0;
    out.push_back(flank);
  }
  return out;
}

std::vector<std::vector<Vec3>> simulate_jiggle(const std::vector<JiggleRegion>& regions,
                                               const std::vector<BoneTransforms>& frames, double rate_hz,
                                               int substeps) {
  if (!(rate_hz > 0.0)) throw std::invalid_argument("simulate_jiggle: rate must be positive");
  if (substeps < 1) throw std::invalid_argument("simulate_jiggle: substeps must be at least 1");
  const size_t n = frames.size();
  const double dt = 1.0 / rate_hz;
  std::vector<std::vector<Vec3>> out(regions.size(), std::vector<Vec3>(n, Vec3::Zero()));
  for (size_t r = 0; r < regions.size(); ++r) {
    const JiggleRegion& reg = regions[r];
    std::vector<Vec3> anchor(n);
    for (size_t f = 0; f < n; ++f) {
      if (reg.anchor_bone < 0 || reg.anchor_bone >= static_cast<int>(frames[f].size()))
        throw std::invalid_argument("simulate_jiggle: region " + reg.name + " has no anchor bone");
      anchor[f] = frames[f][static_cast<size_t>(reg.anchor_bone)] * reg.anchor_point;
    }
    if (n < 3) continue;
    std::vector<Vec3> acc(n, Vec3::Zero());  // mm/s^2
    for (size_t f = 1; f + 1 < n; ++f) acc[f] = (anchor[f + 1] - 2.0 * anchor[f] + anchor[f - 1]) / (dt * dt);
    acc[0] = Vec3::Zero();  // the take starts at rest
    acc[n - 1] = acc[n - 2];
    const double w = 2.0 * M_PI * reg.frequency_hz;
    const double h = dt / substeps;
    Vec3 u = Vec3::Zero(), v = Vec3::Zero();
    for (size_t f = 0; f + 1 < n; ++f) {
      for (int k = 0; k < substeps; ++k) {
        const double s = (k + 0.5) / substeps;
        const Vec3 a = (1.0 - s) * acc[f] + s * acc[f + 1];
        v += h * (-w * w * u - 2.0 * reg.damping_ratio * w * v - reg.gain * a);  // semi-implicit Euler
        u += h * v;
      }
      out[r][f + 1] = saturate(u, reg.max_mm);
    }
  }
  return out;
}

}  // namespace skinstream::synth
