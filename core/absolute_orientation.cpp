#include "core/absolute_orientation.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

namespace skinstream {
namespace {

// For a symmetric 4x4 matrix of rank 3 the adjugate is c v v^T with v the null vector; its
// largest column is the best conditioned. All sixteen cofactors come from twelve shared 2x2
// determinants (the usual 4x4 inverse expansion, without the division).
Eigen::Vector4d best_adjugate_column(const Eigen::Matrix4d& m) {
  const double s0 = m(0, 0) * m(1, 1) - m(1, 0) * m(0, 1), s1 = m(0, 0) * m(1, 2) - m(1, 0) * m(0, 2);
  const double s2 = m(0, 0) * m(1, 3) - m(1, 0) * m(0, 3), s3 = m(0, 1) * m(1, 2) - m(1, 1) * m(0, 2);
  const double s4 = m(0, 1) * m(1, 3) - m(1, 1) * m(0, 3), s5 = m(0, 2) * m(1, 3) - m(1, 2) * m(0, 3);
  const double c5 = m(2, 2) * m(3, 3) - m(3, 2) * m(2, 3), c4 = m(2, 1) * m(3, 3) - m(3, 1) * m(2, 3);
  const double c3 = m(2, 1) * m(3, 2) - m(3, 1) * m(2, 2), c2 = m(2, 0) * m(3, 3) - m(3, 0) * m(2, 3);
  const double c1 = m(2, 0) * m(3, 2) - m(3, 0) * m(2, 2), c0 = m(2, 0) * m(3, 1) - m(3, 0) * m(2, 1);
  Eigen::Matrix4d adj;
  adj(0, 0) = m(1, 1) * c5 - m(1, 2) * c4 + m(1, 3) * c3;
  adj(0, 1) = -m(0, 1) * c5 + m(0, 2) * c4 - m(0, 3) * c3;
  adj(0, 2) = m(3, 1) * s5 - m(3, 2) * s4 + m(3, 3) * s3;
  adj(0, 3) = -m(2, 1) * s5 + m(2, 2) * s4 - m(2, 3) * s3;
  adj(1, 0) = -m(1, 0) * c5 + m(1, 2) * c2 - m(1, 3) * c1;
  adj(1, 1) = m(0, 0) * c5 - m(0, 2) * c2 + m(0, 3) * c1;
  adj(1, 2) = -m(3, 0) * s5 + m(3, 2) * s2 - m(3, 3) * s1;
  adj(1, 3) = m(2, 0) * s5 - m(2, 2) * s2 + m(2, 3) * s1;
  adj(2, 0) = m(1, 0) * c4 - m(1, 1) * c2 + m(1, 3) * c0;
  adj(2, 1) = -m(0, 0) * c4 + m(0, 1) * c2 - m(0, 3) * c0;
  adj(2, 2) = m(3, 0) * s4 - m(3, 1) * s2 + m(3, 3) * s0;
  adj(2, 3) = -m(2, 0) * s4 + m(2, 1) * s2 - m(2, 3) * s0;
  adj(3, 0) = -m(1, 0) * c3 + m(1, 1) * c1 - m(1, 2) * c0;
  adj(3, 1) = m(0, 0) * c3 - m(0, 1) * c1 + m(0, 2) * c0;
  adj(3, 2) = -m(3, 0) * s3 + m(3, 1) * s1 - m(3, 2) * s0;
  adj(3, 3) = m(2, 0) * s3 - m(2, 1) * s1 + m(2, 2) * s0;
  int best = 0;
  adj.colwise().squaredNorm().maxCoeff(&best);
  return adj.col(best);
}

// Horn's 4x4 symmetric matrix from the cross-covariance S = sum a_k b_k^T; its eigenvector with
// the largest eigenvalue is the unit quaternion of the best rotation a -> b.
//
// The matrix is traceless, so its characteristic polynomial is x^4 + c2 x^2 + c1 x + c0 with
// c2 = -2 |S|^2, c1 = -8 det S, c0 = det N, and all roots are real. Newton's method started
// at the upper bound (sum |a|^2 + sum |b|^2) / 2 falls monotonically onto the largest root in a
// few steps (the bound is tight when the fit is good), and the eigenvector is a column of the
// adjugate of N - top I (Theobald's QCP idea). The same quaternion solution as a general
// eigensolver, an order of magnitude cheaper; the general solver stays as the fallback when
// the two largest eigenvalues are too close for the adjugate to be well conditioned.
FitQuality rotation_from_cross_covariance(const Eigen::Matrix3d& s, double bound, int points, Eigen::Matrix3d& out) {
  const double sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const double syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const double szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Eigen::Matrix4d n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;

  FitQuality quality;
  quality.points = points;
  const double scale = n.norm();
  if (!(scale > 1e-300)) {
    out.setIdentity();
    return quality;  // no information at all
  }
  const double c2 = -2.0 * s.squaredNorm(), c1 = -8.0 * s.determinant(), c0 = n.determinant();
  double top = std::min(bound, scale);  // both bound the largest eigenvalue from above
  for (int it = 0; it < 50; ++it) {
    const double value = ((top * top + c2) * top + c1) * top + c0;
    const double slope = (4.0 * top * top + 2.0 * c2) * top + c1;
    if (!(slope > 0.0)) break;
    const double step = value / slope;
    top -= step;
    if (std::abs(step) <= 1e-13 * scale) break;
  }
  Eigen::Vector4d q;
  const Eigen::Vector4d adjugate_column = best_adjugate_column(n - top * Eigen::Matrix4d::Identity());
  // |adj(N - top I)| is the product of top's distances to the other eigenvalues.
  if (adjugate_column.norm() > 1e-6 * scale * scale * scale && adjugate_column.allFinite()) {
    q = adjugate_column.normalized();
    quality.degenerate = points < 3;
  } else {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(n);
    q = eig.eigenvectors().col(3);  // eigenvalues ascending
    const Eigen::Vector4d ev = eig.eigenvalues();
    quality.degenerate = points < 3 || (ev(3) - ev(2)) < 1e-9 * scale;
  }
  out = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized().toRotationMatrix();
  return quality;
}

}  // namespace

FitQuality fit_rotation(std::span<const Vec3> source, std::span<const Vec3> target, Eigen::Matrix3d& out) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  double bound = 0.0;
  for (size_t k = 0; k < source.size(); ++k) {
    s.noalias() += source[k] * target[k].transpose();
    bound += 0.5 * (source[k].squaredNorm() + target[k].squaredNorm());
  }
  if (source.empty()) {
    out.setIdentity();
    return {};
  }
  return rotation_from_cross_covariance(s, bound, static_cast<int>(source.size()), out);
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
  double bound = 0.0;
  for (size_t k = 0; k < source.size(); ++k) {
    const Vec3 a = source[k] - source_mean, b = target[k] - target_mean;
    s.noalias() += a * b.transpose();
    bound += 0.5 * (a.squaredNorm() + b.squaredNorm());
  }
  const FitQuality quality = rotation_from_cross_covariance(s, bound, static_cast<int>(source.size()), out.rotation);
  out.translation = target_mean - out.rotation * source_mean;
  return quality;
}

}  // namespace skinstream
