#include "core/body/skeleton.h"

#include <cmath>
#include <stdexcept>
#include <unordered_set>

namespace skinstream {

Skeleton::Skeleton(std::vector<Bone> bones) : bones_(std::move(bones)) {
  std::unordered_set<std::string> names;
  for (size_t i = 0; i < bones_.size(); ++i) {
    const Bone& b = bones_[i];
    if (b.name.empty()) throw std::invalid_argument("skeleton: bone " + std::to_string(i) + " has no name");
    if (!names.insert(b.name).second) throw std::invalid_argument("skeleton: duplicate bone name " + b.name);
    if (b.parent < -1 || b.parent >= static_cast<int>(i))
      throw std::invalid_argument("skeleton: bone " + b.name + " has parent " + std::to_string(b.parent) +
                                  " (parents must come before their children)");
    if (!b.head.allFinite() || !b.tail.allFinite())
      throw std::invalid_argument("skeleton: bone " + b.name + " has a non-finite joint");
  }
}

int Skeleton::find(const std::string& name) const {
  for (size_t i = 0; i < bones_.size(); ++i)
    if (bones_[i].name == name) return static_cast<int>(i);
  return -1;
}

int Skeleton::require(const std::string& name) const {
  const int i = find(name);
  if (i < 0) throw std::invalid_argument("skeleton: no bone named " + name);
  return i;
}

bool Skeleton::is_descendant(int bone, int ancestor) const {
  while (bone >= 0) {
    if (bone == ancestor) return true;
    bone = bones_.at(static_cast<size_t>(bone)).parent;
  }
  return false;
}

Pose Pose::rest(const Skeleton& skeleton) {
  Pose p;
  p.local.assign(static_cast<size_t>(skeleton.size()), Eigen::Quaterniond::Identity());
  return p;
}

BoneTransforms pose_bones(const Skeleton& skeleton, const Pose& pose) {
  if (static_cast<int>(pose.local.size()) != skeleton.size())
    throw std::invalid_argument("pose_bones: pose has " + std::to_string(pose.local.size()) +
                                " rotations for " + std::to_string(skeleton.size()) + " bones");
  BoneTransforms out(pose.local.size());
  for (int b = 0; b < skeleton.size(); ++b) {
    const Bone& bone = skeleton.bone(b);
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.linear() = pose.local[static_cast<size_t>(b)].normalized().toRotationMatrix();
    local.translation() = bone.head - local.linear() * bone.head;  // rotate about the head
    out[static_cast<size_t>(b)] =
        (bone.parent >= 0 ? out[static_cast<size_t>(bone.parent)] : pose.root) * local;
  }
  return out;
}

double twist_angle(const Eigen::Quaterniond& q, const Vec3& axis) {
  const Vec3 a = axis.normalized();
  double w = q.w();
  double p = q.vec().dot(a);
  if (w < 0.0) {  // same rotation, angle in (-pi, pi]
    w = -w;
    p = -p;
  }
  if (std::abs(w) < 1e-15 && std::abs(p) < 1e-15) return 0.0;  // pure swing by pi
  return 2.0 * std::atan2(p, w);
}

}  // namespace skinstream
