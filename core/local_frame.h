#pragma once
// The local reference frame of eq. 1: origin at the marker, axes (t, b, n) with n the marker
// surface normal, t the first neighbour's direction projected on the tangent plane, b = n x t.

#include <Eigen/Core>
#include <span>

#include "core/capture.h"

namespace skinstream {

// R_i^0 = [t b n]^T. `neighbours` are the one-ring positions; the first one that is not
// parallel to the normal defines t. With no usable neighbour any tangent is chosen.
Eigen::Matrix3d local_reference_frame(const Vec3& marker, const Vec3& normal, std::span<const Vec3> neighbours);

}  // namespace skinstream
