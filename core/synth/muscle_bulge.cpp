#include "core/synth/muscle_bulge.h"

#include <algorithm>
#include <cmath>

namespace skinstream::synth {

namespace {

constexpr double kDeg = M_PI / 180.0;

double smooth(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

Vec3 perpendicular_part(const Vec3& v, const Vec3& axis) {
  const Vec3 p = v - v.dot(axis) * axis;
  return p.norm() > 1e-9 ? Vec3(p.normalized()) : Vec3(Vec3::Zero());
}

std::vector<int> existing(std::initializer_list<int> bones) {
  std::vector<int> out;
  for (int b : bones)
    if (b >= 0) out.push_back(b);
  return out;
}

}  // namespace

std::vector<Muscle> standard_muscles(const Body& body, const Anatomy& a) {
  const Skeleton& sk = body.skeleton;
  std::vector<Muscle> out;
  auto add = [&](Muscle m) {
    if (!m.driver_bones.empty() && !m.region.mask_bones.empty()) out.push_back(std::move(m));
  };
  for (Side s : {kLeft, kRight}) {
    const std::string suffix = std::string("_") + side_suffix(s);
    const double l = lateral_sign(s);
    const ArmBones& arm = a.arm[s];
    const LegBones& leg = a.leg[s];
    const double upper_len = (a.elbow_joint[s] - a.shoulder_joint[s]).norm();
    const double fore_len = (a.wrist_joint[s] - a.elbow_joint[s]).norm();
    const double thigh_len = (a.knee_joint[s] - a.hip_joint[s]).norm();
    const double shank_len = (a.ankle_joint[s] - a.knee_joint[s]).norm();
    const Vec3 arm_front =
        perpendicular_part(a.forearm_dir[s], a.upperarm_dir[s]);  // toward the flexing forearm
    const Vec3 fore_front = perpendicular_part(-a.upperarm_dir[s], a.forearm_dir[s]);

    Muscle biceps;
    biceps.name = "biceps" + suffix;
    biceps.region.centre = a.shoulder_joint[s] + 0.55 * (a.elbow_joint[s] - a.shoulder_joint[s]);
    biceps.region.axis = a.upperarm_dir[s];
    biceps.region.sigma_along = 0.2 * upper_len;
    biceps.region.facing = arm_front;
    biceps.region.facing_power = 1.5;
    biceps.region.mask_bones = existing({arm.upperarm, arm.upperarm_twist});
    biceps.driver_bones = existing({arm.elbow});
    biceps.driver_axis = a.elbow_axis[s];
    biceps.full_angle = 140 * kDeg - a.elbow_rest_flex[s];  // from the rest pose to full flexion
    biceps.amplitude_mm = 12.0;
    biceps.effort_mm = 8.0;
    add(biceps);

    Muscle triceps = biceps;  // firms up under effort only
    triceps.name = "triceps" + suffix;
    triceps.region.centre = a.shoulder_joint[s] + 0.45 * (a.elbow_joint[s] - a.shoulder_joint[s]);
    triceps.region.sigma_along = 0.25 * upper_len;
    triceps.region.facing = -arm_front;
    triceps.amplitude_mm = 0.0;
    triceps.effort_mm = 4.0;
    add(triceps);

    Muscle forearm;
    forearm.name = "forearm" + suffix;
    forearm.region.centre = a.elbow_joint[s] + 0.3 * (a.wrist_joint[s] - a.elbow_joint[s]);
    forearm.region.axis = a.forearm_dir[s];
    forearm.region.sigma_along = 0.22 * fore_len;
    forearm.region.facing = fore_front;
    forearm.region.facing_power = 1.0;
    forearm.region.mask_bones = existing({arm.elbow, arm.forearm_twist});
    forearm.driver_bones = existing({arm.elbow});
    forearm.driver_axis = a.elbow_axis[s];
    forearm.full_angle = 140 * kDeg - a.elbow_rest_flex[s];
    forearm.amplitude_mm = 4.0;
    forearm.effort_mm = 4.0;
    add(forearm);

    Muscle deltoid;
    deltoid.name = "deltoid" + suffix;
    deltoid.region.centre = a.shoulder_joint[s] + 0.12 * (a.elbow_joint[s] - a.shoulder_joint[s]);
    deltoid.region.axis = a.upperarm_dir[s];
    deltoid.region.sigma_along = 0.2 * upper_len;
    deltoid.region.facing = (l * kAxisRight + 0.6 * kAxisUp).normalized();
    deltoid.region.facing_power = 1.0;
    deltoid.region.mask_bones = existing({arm.upperarm, arm.shoulder});
    deltoid.driver = Muscle::Driver::kSwing;
    deltoid.driver_bones = existing({arm.upperarm});
    deltoid.driver_axis = a.upperarm_dir[s];
    deltoid.full_angle = 90 * kDeg;
    deltoid.amplitude_mm = 6.0;
    deltoid.effort_mm = 3.0;
    add(deltoid);

    Muscle pectoral;
    pectoral.name = "pectoral" + suffix;
    pectoral.region.centre = 0.55 * a.shoulder_joint[s] +
                             0.45 * Vec3(0.0, a.shoulder_joint[s].y(), a.shoulder_joint[s].z()) -
                             70.0 * kAxisUp + 80.0 * kAxisForward;
    pectoral.region.sigma_along = 80.0;
    pectoral.region.sigma_across = 80.0;
    pectoral.region.facing = kAxisForward;
    pectoral.region.facing_power = 1.0;
    pectoral.region.mask_bones =
        existing({a.spine[3], a.spine[4], sk.find(std::string("breast.") + side_suffix(s)), arm.clavicle,
                  arm.shoulder});
    pectoral.driver = Muscle::Driver::kSwing;
    pectoral.driver_bones = existing({arm.upperarm});
    pectoral.driver_axis = a.upperarm_dir[s];
    pectoral.full_angle = 110 * kDeg;
    pectoral.amplitude_mm = 4.0;
    pectoral.effort_mm = 5.0;
    add(pectoral);

    Muscle quads;
    quads.name = "quadriceps" + suffix;
    quads.region.centre = a.hip_joint[s] + 0.6 * (a.knee_joint[s] - a.hip_joint[s]);
    quads.region.axis = a.thigh_dir[s];
    quads.region.sigma_along = 0.22 * thigh_len;
    quads.region.facing = perpendicular_part(kAxisForward, a.thigh_dir[s]);
    quads.region.facing_power = 1.2;
    quads.region.mask_bones = existing({leg.hip, leg.thigh_twist});
    quads.driver_bones = existing({leg.knee});
    quads.driver_axis = -kAxisRight;
    quads.full_angle = 110 * kDeg;
    quads.amplitude_mm = 6.0;
    quads.effort_mm = 5.0;
    add(quads);

    Muscle hams = quads;
    hams.name = "hamstrings" + suffix;
    hams.region.centre = a.hip_joint[s] + 0.55 * (a.knee_joint[s] - a.hip_joint[s]);
    hams.region.facing = -quads.region.facing;
    hams.amplitude_mm = 7.0;
    hams.effort_mm = 3.0;
    add(hams);

    Muscle calf;
    calf.name = "calf" + suffix;
    calf.region.centre = a.knee_joint[s] + 0.3 * (a.ankle_joint[s] - a.knee_joint[s]);
    calf.region.axis = a.shank_dir[s];
    calf.region.sigma_along = 0.18 * shank_len;
    calf.region.facing = perpendicular_part(-kAxisForward, a.shank_dir[s]);
    calf.region.facing_power = 1.0;
    calf.region.mask_bones = existing({leg.knee, leg.shank_twist});
    calf.driver_bones = existing({leg.ankle});
    calf.driver_axis = -kAxisRight;  // plantarflexion
    calf.full_angle = 30 * kDeg;
    calf.amplitude_mm = 6.0;
    calf.effort_mm = 5.0;
    add(calf);

    Muscle glute;
    glute.name = "gluteus" + suffix;
    glute.region.centre = a.hip_joint[s] - 70.0 * kAxisForward + 10.0 * kAxisUp;
    glute.region.sigma_along = 90.0;
    glute.region.sigma_across = 90.0;
    glute.region.facing = -kAxisForward;
    glute.region.mask_bones = existing({leg.pelvis, leg.hip, a.root, a.spine[0]});
    glute.driver = Muscle::Driver::kSwing;
    glute.driver_bones = existing({leg.hip});
    glute.driver_axis = a.thigh_dir[s];
    glute.full_angle = 90 * kDeg;
    glute.amplitude_mm = 4.0;
    glute.effort_mm = 4.0;
    add(glute);
  }

  Muscle abs;
  abs.name = "abdominals";
  abs.region.centre = 0.5 * (body.skeleton.bone(a.spine[1]).head + body.skeleton.bone(a.spine[2]).head) +
                      100.0 * kAxisForward;
  abs.region.axis = kAxisUp;
  abs.region.sigma_along = 120.0;
  abs.region.sigma_across = 150.0;
  abs.region.facing = kAxisForward;
  abs.region.facing_power = 1.5;
  abs.region.mask_bones = existing({a.spine[0], a.spine[1], a.spine[2], a.root});
  abs.driver_bones = existing({a.spine[0], a.spine[1], a.spine[2], a.spine[3], a.spine[4]});
  abs.driver_axis = -kAxisRight;  // forward bend
  abs.full_angle = 60 * kDeg;
  abs.amplitude_mm = 9.0;
  abs.effort_mm = 3.0;
  add(abs);
  return out;
}

double muscle_activation(const Muscle& m, const Pose& pose) {
  double angle = 0.0;
  for (int b : m.driver_bones) {
    const Eigen::Quaterniond& q = pose.local[static_cast<size_t>(b)];
    if (m.driver == Muscle::Driver::kAboutAxis) {
      angle += twist_angle(q, m.driver_axis);
    } else {
      const Vec3 d = m.driver_axis.normalized();
      angle += std::acos(std::clamp((q * d).dot(d), -1.0, 1.0));
    }
  }
  return smooth((angle - m.zero_angle) / m.full_angle);
}

double muscle_bulge_mm(const Muscle& m, const Pose& pose, double effort) {
  const double a = muscle_activation(m, pose);
  effort = std::clamp(effort, 0.0, 1.0);
  return m.amplitude_mm * a * (0.6 + 0.4 * effort) + m.effort_mm * effort * (0.5 + 0.5 * a);
}

}  // namespace skinstream::synth
