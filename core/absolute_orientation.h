#pragma once
// Absolute orientation by Horn's closed-form unit-quaternion method (Horn 1987), used by the
// paper's eq. 2 (rigid fit of neighbours), eq. 5 (rotation-only local frame) and the per-part
// rigid transforms of section 5.3. Allocation-free: callers pass spans over their own buffers.

#include <Eigen/Core>
#include <span>

#include "core/capture.h"

namespace skinstream {

struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();

  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
  Vec3 apply_inverse(const Vec3& p) const { return rotation.transpose() * (p - translation); }
};

struct FitQuality {
  int points = 0;
  // True when the rotation is not pinned down (fewer than 3 points, or collinear/coincident
  // points): the result still minimises the error but the rotation about the line is arbitrary.
  bool degenerate = true;
};

// R, t minimising sum_k ||R * source[k] + t - target[k]||^2. Always a proper rotation (det +1),
// also for reflected inputs. Spans must have equal length; an empty span gives the identity.
FitQuality fit_rigid(std::span<const Vec3> source, std::span<const Vec3> target, RigidTransform& out);

// Rotation only, about the origin: R minimising sum_k ||R * source[k] - target[k]||^2 (eq. 5).
FitQuality fit_rotation(std::span<const Vec3> source, std::span<const Vec3> target, Eigen::Matrix3d& out);

}  // namespace skinstream
