#include "core/synth/motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skinstream::synth {

namespace {
constexpr double kRad = 180.0 / M_PI;
constexpr double kBlendIn = 0.8;  // s from the rest pose into the motion

double smooth(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}
}  // namespace

double tidal_breath(double t, double period_s) { return 0.225 * (1.0 - std::cos(2.0 * M_PI * t / period_s)); }

JointAngles rest_angles(const Anatomy& anatomy) {
  JointAngles a;
  for (Side s : {kLeft, kRight}) {
    const Vec3 d = anatomy.upperarm_dir[s];
    a.arm[s].elevation = std::acos(std::clamp(-d.z(), -1.0, 1.0)) * kRad;
    a.arm[s].plane = std::atan2(d.y(), lateral_sign(s) * d.x()) * kRad;
    a.arm[s].elbow = anatomy.elbow_rest_flex[s] * kRad;
  }
  return a;
}

JointAngles blend(const JointAngles& a, const JointAngles& b, double w) {
  auto mix = [w](double x, double y) { return x + w * (y - x); };
  JointAngles o;
  o.spine_flex = mix(a.spine_flex, b.spine_flex);
  o.spine_side = mix(a.spine_side, b.spine_side);
  o.spine_twist = mix(a.spine_twist, b.spine_twist);
  o.neck_flex = mix(a.neck_flex, b.neck_flex);
  o.neck_side = mix(a.neck_side, b.neck_side);
  o.neck_twist = mix(a.neck_twist, b.neck_twist);
  for (int s = 0; s < 2; ++s) {
    const auto &x = a.arm[s], &y = b.arm[s];
    auto& z = o.arm[s];
    z.clavicle_elevate = mix(x.clavicle_elevate, y.clavicle_elevate);
    z.clavicle_protract = mix(x.clavicle_protract, y.clavicle_protract);
    z.plane = mix(x.plane, y.plane);
    z.elevation = mix(x.elevation, y.elevation);
    z.twist = mix(x.twist, y.twist);
    z.elbow = mix(x.elbow, y.elbow);
    z.pronation = mix(x.pronation, y.pronation);
    z.wrist = mix(x.wrist, y.wrist);
    const auto &p = a.leg[s], &q = b.leg[s];
    auto& r = o.leg[s];
    r.plane = mix(p.plane, q.plane);
    r.elevation = mix(p.elevation, q.elevation);
    r.twist = mix(p.twist, q.twist);
    r.knee = mix(p.knee, q.knee);
    r.ankle = mix(p.ankle, q.ankle);
  }
  o.translation = a.translation + w * (b.translation - a.translation);
  o.yaw = mix(a.yaw, b.yaw);
  o.pitch = mix(a.pitch, b.pitch);
  o.roll = mix(a.roll, b.roll);
  o.clearance = mix(a.clearance, b.clearance);
  o.breath = mix(a.breath, b.breath);
  o.effort = mix(a.effort, b.effort);
  return o;
}

Pose build_pose(const Skeleton& skeleton, const Anatomy& anatomy, const JointAngles& j) {
  PoseBuilder b(skeleton, anatomy);
  b.spine(j.spine_flex, j.spine_side, j.spine_twist);
  b.neck(j.neck_flex, j.neck_side, j.neck_twist);
  for (Side s : {kLeft, kRight}) {
    const auto& arm = j.arm[s];
    b.clavicle(s, arm.clavicle_elevate, arm.clavicle_protract);
    b.shoulder(s, arm.plane, arm.elevation, arm.twist);
    b.elbow(s, arm.elbow);
    b.forearm_twist(s, arm.pronation);
    b.wrist(s, arm.wrist);
    const auto& leg = j.leg[s];
    b.hip(s, leg.plane, leg.elevation, leg.twist);
    b.knee(s, leg.knee);
    b.ankle(s, leg.ankle);
  }
  b.body(j.translation, j.yaw, j.pitch, j.roll);
  return b.pose();
}

const std::vector<std::string>& motion_names() {
  static const std::vector<std::string> names = {"rom", "breathe", "flex", "golf", "punch", "jumprope", "medley", "static"};
  return names;
}

bool is_motion(const std::string& name) {
  const auto& n = motion_names();
  return std::find(n.begin(), n.end(), name) != n.end();
}

JointAngles motion_target_angles(const std::string& name, const Anatomy& anatomy, double t, double duration) {
  if (name == "rom") return rom_motion(anatomy, t, duration);
  if (name == "breathe") return breathe_motion(anatomy, t);
  if (name == "flex") return flex_motion(anatomy, t);
  if (name == "golf") return golf_motion(anatomy, t);
  if (name == "punch") return punch_motion(anatomy, t);
  if (name == "jumprope") return jumprope_motion(anatomy, t);
  if (name == "medley") return medley_motion(anatomy, t, duration);
  if (name == "static") {
    JointAngles target = rest_angles(anatomy);
    target.breath = tidal_breath(t);
    return target;
  }
  throw std::invalid_argument("unknown motion '" + name + "' (known: rom, breathe, flex, golf, punch, jumprope, medley, static)");
}

JointAngles motion_angles(const std::string& name, const Anatomy& anatomy, double t, double duration) {
  return blend(rest_angles(anatomy), motion_target_angles(name, anatomy, t, duration), smooth(t / kBlendIn));
}

MotionSample sample_motion(const std::string& name, const Skeleton& skeleton, const Anatomy& anatomy,
                           double t, double duration) {
  const JointAngles j = motion_angles(name, anatomy, t, duration);
  MotionSample s;
  s.pose = build_pose(skeleton, anatomy, j);
  const double dz = ground_offset(anatomy, pose_bones(skeleton, s.pose), j.clearance);
  s.pose.root.pretranslate(Vec3(0.0, 0.0, dz));
  s.breath = std::clamp(j.breath, 0.0, 1.0);
  s.effort = std::clamp(j.effort, 0.0, 1.0);
  return s;
}

JointAngles interpolate_keys(const std::vector<AngleKey>& keys, double t, bool loop) {
  if (keys.empty()) throw std::invalid_argument("interpolate_keys: no keys");
  if (keys.size() == 1) return keys.front().angles;
  const double t0 = keys.front().time, t1 = keys.back().time;
  if (loop && t1 > t0) {
    t = std::fmod(t - t0, t1 - t0);
    if (t < 0) t += t1 - t0;
    t += t0;
  }
  if (t <= t0) return keys.front().angles;
  if (t >= t1) return keys.back().angles;
  size_t i = 1;
  while (keys[i].time < t) ++i;
  const AngleKey& a = keys[i - 1];
  const AngleKey& b = keys[i];
  const double span = b.time - a.time;
  const double u = span > 0 ? (t - a.time) / span : 1.0;
  return blend(a.angles, b.angles, 0.5 - 0.5 * std::cos(M_PI * u));
}

}  // namespace skinstream::synth
