#include "core/rigid_fit_leverage.h"

#include <Eigen/LU>

namespace skinstream {
namespace {

Eigen::Matrix3d cross_matrix(const Vec3& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace

// Linearised about a perfect fit: the translation takes 1/n of the error, and the rotation
// w = I^-1 sum_k s_k x delta_k (I the centred points' inertia tensor) carries the centroid c,
// so the origin moves by delta_k / n + c x w. The inertia gets a floor of 1e-9 of its trace, so
// that collinear points, which do not determine the turn about their line, give huge leverages
// rather than infinite ones.
void rigid_fit_leverage(std::span<const Vec3> source, std::span<double> out_leverage) {
  const int n = static_cast<int>(source.size());
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : source) centroid += p;
  centroid /= n;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const Vec3& p : source) {
    const Vec3 s = p - centroid;
    inertia += s.squaredNorm() * Eigen::Matrix3d::Identity() - s * s.transpose();
  }
  constexpr double kInertiaFloor = 1e-9;
  inertia += (kInertiaFloor * inertia.trace() + 1e-12) * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d carry = cross_matrix(centroid) * inertia.inverse();
  for (int k = 0; k < n; ++k) {
    const Eigen::Matrix3d jacobian = Eigen::Matrix3d::Identity() / n + carry * cross_matrix(source[k] - centroid);
    out_leverage[k] = jacobian.squaredNorm() / 3.0;
  }
}

}  // namespace skinstream
