#include "core/absolute_orientation.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace skinstream {
namespace {

// Horn's 4x4 symmetric matrix from the cross-covariance S = sum a_k b_k^T; its eigenvector with
// the largest eigenvalue is the unit quaternion of the best rotation a -> b.
FitQuality rotation_from_cross_covariance(const Eigen::Matrix3d& s, int points, Eigen::Matrix3d& out) {
  const double sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const double syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const double szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Eigen::Matrix4d n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(n);
  const Eigen::Vector4d q = eig.eigenvectors().col(3);  // eigenvalues ascending
  out = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();

  FitQuality quality;
  quality.points = points;
  // A unique optimum needs a gap between the two largest eigenvalues; relative to the scale of
  // the data so that millimetre and metre inputs behave alike.
  const Eigen::Vector4d ev = eig.eigenvalues();
  const double scale = std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
  quality.degenerate = points < 3 || (ev(3) - ev(2)) < 1e-9 * scale || s.norm() < 1e-300;
  return quality;
}

}  // namespace

FitQuality fit_rotation(std::span<const Vec3> source, std::span<const Vec3> target, Eigen::Matrix3d& out) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < source.size(); ++k) s.noalias() += source[k] * target[k].transpose();
  if (source.empty()) {
    out.setIdentity();
    return {};
  }
  return rotation_from_cross_covariance(s, static_cast<int>(source.size()), out);
}

FitQuality fit_rigid(std::span<const Vec3> source, std::span<const Vec3> target, RigidTransform& out) {
  out = RigidTransform{};
  if (source.empty()) return {};
  Vec3 source_mean = Vec3::Zero(), target_mean = Vec3::Zero();
  for (size_t k = 0; k < source.size(); ++k) {
    source_mean += source[k];
    target_mean += target[k];
  }
  source_mean /= static_cast<double>(source.size());
  target_mean /= static_cast<double>(source.size());
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < source.size(); ++k)
    s.noalias() += (source[k] - source_mean) * (target[k] - target_mean).transpose();
  const FitQuality quality = rotation_from_cross_covariance(s, static_cast<int>(source.size()), out.rotation);
  out.translation = target_mean - out.rotation * source_mean;
  return quality;
}

}  // namespace skinstream
