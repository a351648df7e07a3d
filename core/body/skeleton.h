#pragma once
// A bone hierarchy in its rest pose and the forward kinematics that poses it.
//
// Conventions (core/body and everything built on it): millimetres, Z up, the subject faces +Y, its left side is
// on -X. A bone rotates about its head joint. Pose::local[b] is the rotation of bone b about
// its head expressed in rest-pose axes, relative to its parent (applied after the parent's
// motion), so at rest every local rotation is the identity and every bone transform is the
// identity. A bone transform maps a rest-pose point rigidly attached to the bone to its posed
// position (the matrix linear blend skinning blends).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct Bone {
  std::string name;
  int parent = -1;  // index of the parent bone, -1 for a root
  Vec3 head = Vec3::Zero();
  Vec3 tail = Vec3::Zero();

  Vec3 axis() const { return (tail - head).normalized(); }
  double length() const { return (tail - head).norm(); }
};

class Skeleton {
 public:
  Skeleton() = default;
  // Throws std::invalid_argument for an empty name, a duplicate name, a parent index out of
  // range or not before its child (parents must come first), or a non-finite joint.
  explicit Skeleton(std::vector<Bone> bones);

  int size() const { return static_cast<int>(bones_.size()); }
  bool empty() const { return bones_.empty(); }
  const Bone& bone(int i) const { return bones_.at(static_cast<size_t>(i)); }
  const std::vector<Bone>& bones() const { return bones_; }
  int find(const std::string& name) const;           // -1 when absent
  int require(const std::string& name) const;        // throws std::invalid_argument when absent
  bool is_descendant(int bone, int ancestor) const;  // bone == ancestor counts

 private:
  std::vector<Bone> bones_;
};

struct Pose {
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();  // whole-body rigid motion, applied last
  std::vector<Eigen::Quaterniond> local;                   // one per bone, identity at rest

  static Pose rest(const Skeleton& skeleton);
};

using BoneTransforms = std::vector<Eigen::Isometry3d>;

// The rest-to-posed transform of every bone. Throws std::invalid_argument when the pose does
// not have one rotation per bone.
BoneTransforms pose_bones(const Skeleton& skeleton, const Pose& pose);

// Signed angle (radians, in (-pi, pi]) of the twist of q about the unit axis: the rotation
// about `axis` left after removing the swing (swing-twist decomposition).
double twist_angle(const Eigen::Quaterniond& q, const Vec3& axis);

// Rotation by `angle` radians about the unit `axis`.
inline Eigen::Quaterniond rotation(const Vec3& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

}  // namespace skinstream
