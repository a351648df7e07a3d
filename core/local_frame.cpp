#include "core/local_frame.h"

#include <Eigen/Geometry>

namespace skinstream {

Eigen::Matrix3d local_reference_frame(const Vec3& marker, const Vec3& normal, std::span<const Vec3> neighbours) {
  Vec3 n = normal.normalized();
  if (!n.allFinite() || n.norm() < 0.5) n = Vec3::UnitZ();
  Vec3 t = Vec3::Zero();
  for (const Vec3& p : neighbours) {
    const Vec3 v = p - marker;
    const Vec3 tangential = v - v.dot(n) * n;
    if (tangential.norm() > 1e-6 * std::max(1.0, v.norm())) {
      t = tangential.normalized();
      break;
    }
  }
  if (t.isZero()) t = n.unitOrthogonal();
  const Vec3 b = n.cross(t);
  Eigen::Matrix3d r;
  r.row(0) = t.transpose();
  r.row(1) = b.transpose();
  r.row(2) = n.transpose();
  return r;
}

}  // namespace skinstream
