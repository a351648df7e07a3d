#include "core/body/anatomy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skinstream {

namespace {

constexpr double kDeg = M_PI / 180.0;

int find_sided(const Skeleton& sk, const std::string& base, Side s) {
  return sk.find(base + "." + side_suffix(s));
}

Vec3 tail_or_child_head(const Skeleton& sk, int bone) { return sk.bone(bone).tail; }

}  // namespace

Anatomy Anatomy::from(const Body& body) {
  const Skeleton& sk = body.skeleton;
  Anatomy a;
  a.root = sk.find("root");
  const char* spine_names[5] = {"spine05", "spine04", "spine03", "spine02", "spine01"};
  for (int i = 0; i < 5; ++i) a.spine[static_cast<size_t>(i)] = sk.find(spine_names[i]);
  a.neck = {sk.find("neck01"), sk.find("neck02"), sk.find("neck03")};
  a.head = sk.find("head");
  for (Side s : {kLeft, kRight}) {
    ArmBones& arm = a.arm[s];
    arm.clavicle = find_sided(sk, "clavicle", s);
    arm.shoulder = find_sided(sk, "shoulder01", s);
    arm.upperarm = find_sided(sk, "upperarm01", s);
    arm.upperarm_twist = find_sided(sk, "upperarm02", s);
    arm.elbow = find_sided(sk, "lowerarm01", s);
    arm.forearm_twist = find_sided(sk, "lowerarm02", s);
    arm.wrist = find_sided(sk, "wrist", s);
    LegBones& leg = a.leg[s];
    leg.pelvis = find_sided(sk, "pelvis", s);
    leg.hip = find_sided(sk, "upperleg01", s);
    leg.thigh_twist = find_sided(sk, "upperleg02", s);
    leg.knee = find_sided(sk, "lowerleg01", s);
    leg.shank_twist = find_sided(sk, "lowerleg02", s);
    leg.ankle = find_sided(sk, "foot", s);
    const std::string side = std::string(".") + side_suffix(s);
    if (arm.upperarm < 0 || arm.elbow < 0 || leg.hip < 0 || leg.knee < 0 || leg.ankle < 0)
      throw std::invalid_argument("anatomy: skeleton lacks upperarm01/lowerarm01/upperleg01/lowerleg01/foot" +
                                  side);
  }
  if (a.spine[0] < 0 || a.spine[4] < 0)
    throw std::invalid_argument("anatomy: skeleton lacks spine05/spine01");

  for (Side s : {kLeft, kRight}) {
    const ArmBones& arm = a.arm[s];
    const LegBones& leg = a.leg[s];
    a.shoulder_joint[s] = sk.bone(arm.upperarm).head;
    a.elbow_joint[s] = sk.bone(arm.elbow).head;
    a.wrist_joint[s] = tail_or_child_head(sk, arm.forearm_twist >= 0 ? arm.forearm_twist : arm.elbow);
    a.hip_joint[s] = sk.bone(leg.hip).head;
    a.knee_joint[s] = sk.bone(leg.knee).head;
    a.ankle_joint[s] = sk.bone(leg.ankle).head;
    a.upperarm_dir[s] = (a.elbow_joint[s] - a.shoulder_joint[s]).normalized();
    a.forearm_dir[s] = (a.wrist_joint[s] - a.elbow_joint[s]).normalized();
    a.thigh_dir[s] = (a.knee_joint[s] - a.hip_joint[s]).normalized();
    a.shank_dir[s] = (a.ankle_joint[s] - a.knee_joint[s]).normalized();
    // Elbow hinge: perpendicular to upper arm and forearm when the rest pose is bent; for a
    // straight rest arm, perpendicular to the arm and the forward direction.
    Vec3 axis = a.upperarm_dir[s].cross(a.forearm_dir[s]);
    if (axis.norm() < 0.2) axis = a.forearm_dir[s].cross(kAxisForward);  // flexes toward the front
    a.elbow_axis[s] = axis.normalized();
    a.elbow_rest_flex[s] = std::acos(std::clamp(a.upperarm_dir[s].dot(a.forearm_dir[s]), -1.0, 1.0));
  }
  a.hip_centre = 0.5 * (a.hip_joint[kLeft] + a.hip_joint[kRight]);

  // Sole points: heel (rearmost) and ball (foremost) among the lowest vertices of each foot.
  std::array<double, 2> min_z{std::numeric_limits<double>::infinity(),
                              std::numeric_limits<double>::infinity()};
  std::array<std::vector<int>, 2> foot_vertices;
  for (int v = 0; v < body.vertex_count(); ++v) {
    const int d = body.weights.dominant(v);
    for (Side s : {kLeft, kRight})
      if (sk.is_descendant(d, a.leg[s].ankle)) {
        foot_vertices[s].push_back(v);
        min_z[s] = std::min(min_z[s], body.rest[static_cast<size_t>(v)].z());
      }
  }
  for (Side s : {kLeft, kRight}) {
    if (foot_vertices[s].empty()) {
      a.sole_points[s] = {a.ankle_joint[s]};
      continue;
    }
    Vec3 heel = Vec3::Zero(), ball = Vec3::Zero();
    double hy = std::numeric_limits<double>::infinity(), by = -hy;
    for (int v : foot_vertices[s]) {
      const Vec3& p = body.rest[static_cast<size_t>(v)];
      if (p.z() > min_z[s] + 12.0) continue;
      if (p.y() < hy) hy = p.y(), heel = p;
      if (p.y() > by) by = p.y(), ball = p;
    }
    a.sole_points[s] = {heel, ball};
  }
  return a;
}

PoseBuilder::PoseBuilder(const Skeleton& skeleton, const Anatomy& anatomy)
    : skeleton_(skeleton), anatomy_(anatomy), pose_(Pose::rest(skeleton)) {}

void PoseBuilder::rotate(int bone, const Vec3& axis, double degrees) {
  if (bone < 0 || degrees == 0.0) return;
  Eigen::Quaterniond& q = pose_.local[static_cast<size_t>(bone)];
  q = (rotation(axis, degrees * kDeg) * q).normalized();
}

void PoseBuilder::spine(double flex, double side_bend, double twist) {
  static const double share[5] = {0.16, 0.22, 0.24, 0.22, 0.16};
  for (int i = 0; i < 5; ++i) {
    const int b = anatomy_.spine[static_cast<size_t>(i)];
    rotate(b, -kAxisRight, flex * share[i]);
    rotate(b, kAxisForward, side_bend * share[i]);
    rotate(b, kAxisUp, twist * share[i]);
  }
}

void PoseBuilder::neck(double flex, double side_bend, double twist) {
  const int bones[4] = {anatomy_.neck[0], anatomy_.neck[1], anatomy_.neck[2], anatomy_.head};
  static const double share[4] = {0.3, 0.25, 0.2, 0.25};
  for (int i = 0; i < 4; ++i) {
    rotate(bones[i], -kAxisRight, flex * share[i]);
    rotate(bones[i], kAxisForward, side_bend * share[i]);
    rotate(bones[i], kAxisUp, twist * share[i]);
  }
}

void PoseBuilder::swing(int bone, const Vec3& rest_dir, const Vec3& target_dir, double twist) {
  if (bone < 0) return;
  const Eigen::Quaterniond q = rotation(target_dir, twist * kDeg) *
                               Eigen::Quaterniond::FromTwoVectors(rest_dir, target_dir.normalized());
  Eigen::Quaterniond& local = pose_.local[static_cast<size_t>(bone)];
  local = (q * local).normalized();
}

void PoseBuilder::shoulder(Side s, double plane, double elevation, double twist) {
  const Vec3 lateral = lateral_sign(s) * kAxisRight;
  const double p = plane * kDeg, e = elevation * kDeg;
  const Vec3 horizontal = std::cos(p) * lateral + std::sin(p) * kAxisForward;
  const Vec3 target = std::cos(e) * -kAxisUp + std::sin(e) * horizontal;
  // Internal rotation turns the front of the arm medially: about the arm pointing distally, a
  // negative right-hand rotation on the right side and a positive one on the left.
  swing(anatomy_.arm[s].upperarm, anatomy_.upperarm_dir[s], target, -lateral_sign(s) * twist);
}

void PoseBuilder::clavicle(Side s, double elevate, double protract) {
  const double l = lateral_sign(s);
  rotate(anatomy_.arm[s].clavicle, -l * kAxisForward, elevate);
  rotate(anatomy_.arm[s].clavicle, l * kAxisUp, protract);
}

void PoseBuilder::elbow(Side s, double flex) {
  rotate(anatomy_.arm[s].elbow, anatomy_.elbow_axis[s], flex - anatomy_.elbow_rest_flex[s] / kDeg);
}

void PoseBuilder::forearm_twist(Side s, double pronation) {
  rotate(anatomy_.arm[s].forearm_twist, anatomy_.forearm_dir[s], -lateral_sign(s) * pronation);
}

void PoseBuilder::wrist(Side s, double flex) { rotate(anatomy_.arm[s].wrist, anatomy_.elbow_axis[s], flex); }

void PoseBuilder::hip(Side s, double plane, double elevation, double twist) {
  const Vec3 d = anatomy_.thigh_dir[s];
  const double p = plane * kDeg, e = elevation * kDeg;
  const Vec3 horizontal = std::cos(p) * lateral_sign(s) * kAxisRight + std::sin(p) * kAxisForward;
  Vec3 perp = horizontal - horizontal.dot(d) * d;
  perp.normalize();
  const Vec3 target = std::cos(e) * d + std::sin(e) * perp;
  swing(anatomy_.leg[s].hip, d, target, -lateral_sign(s) * twist);
}

void PoseBuilder::knee(Side s, double flex) { rotate(anatomy_.leg[s].knee, -kAxisRight, flex); }

void PoseBuilder::ankle(Side s, double dorsiflex) { rotate(anatomy_.leg[s].ankle, kAxisRight, dorsiflex); }

void PoseBuilder::body(const Vec3& translation, double yaw, double pitch, double roll) {
  const Eigen::Matrix3d r = (rotation(kAxisUp, yaw * kDeg) * rotation(-kAxisRight, pitch * kDeg) *
                             rotation(kAxisForward, roll * kDeg))
                                .toRotationMatrix();
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = r;
  m.translation() = translation + anatomy_.hip_centre - r * anatomy_.hip_centre;
  pose_.root = m;
}

double ground_offset(const Anatomy& anatomy, const BoneTransforms& bones, double clearance) {
  double lowest = std::numeric_limits<double>::infinity();
  for (Side s : {kLeft, kRight})
    for (const Vec3& p : anatomy.sole_points[s])
      lowest = std::min(lowest, (bones[static_cast<size_t>(anatomy.leg[s].ankle)] * p).z());
  return std::isfinite(lowest) ? clearance - lowest : 0.0;
}

}  // namespace skinstream
