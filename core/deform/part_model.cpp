#include "core/deform/part_model.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skinstream {
namespace {

// Singular values below this fraction of the largest are treated as zero (rank-revealing).
constexpr double kRelativeRankTolerance = 1e-9;

RigidTransform principal_frame(const std::vector<Vec3>& points) {
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  covariance /= static_cast<double>(points.size());

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Matrix3d axes = eigen.eigenvectors().rowwise().reverse();  // largest variance first
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);          // proper rotation

  RigidTransform frame;
  frame.rotation = axes.transpose();
  frame.translation = -frame.rotation * mean;
  return frame;
}

double largest_nearest_member_distance(const std::vector<Vec3>& points) {
  double largest = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < points.size(); ++j)
      if (j != i) nearest = std::min(nearest, (points[i] - points[j]).norm());
    if (std::isfinite(nearest)) largest = std::max(largest, nearest);
  }
  return largest;
}

}  // namespace

PartModel build_part_model(const std::vector<Vec3>& reference_member_positions, double quadratic_ridge) {
  if (reference_member_positions.empty()) throw std::invalid_argument("build_part_model: no members");
  for (const Vec3& p : reference_member_positions)
    if (!is_present(p)) throw std::invalid_argument("build_part_model: non-finite member position");
  if (!(quadratic_ridge >= 0.0) || !std::isfinite(quadratic_ridge))
    throw std::invalid_argument("build_part_model: quadratic ridge must be finite and not negative");

  PartModel model;
  model.quadratic_ridge = quadratic_ridge;
  const int count = static_cast<int>(reference_member_positions.size());
  model.reference_frame = principal_frame(reference_member_positions);
  model.local_reference_points.resize(count);
  model.local_reference.resize(3, count);
  model.quadratic_reference.resize(9, count);
  double squared_radius = 0.0;
  for (int i = 0; i < count; ++i) {
    const Vec3 local = model.reference_frame.apply(reference_member_positions[i]);
    model.local_reference_points[i] = local;
    model.local_reference.col(i) = local;
    model.quadratic_reference.col(i) = quadratic_basis(local);
    squared_radius += local.squaredNorm();
  }

  // Pseudo-inverse in coordinates scaled to unit RMS radius: in mm the quadratic rows are ~1e4
  // times the linear ones, which would make the rank decision depend on the part's size.
  double scale = std::sqrt(squared_radius / count);
  if (!(scale > 1e-12)) scale = 1.0;
  QuadraticVector row_scale;
  row_scale << scale, scale, scale, scale * scale, scale * scale, scale * scale, scale * scale,
      scale * scale, scale * scale;
  const Eigen::MatrixXd scaled = row_scale.cwiseInverse().asDiagonal() * model.quadratic_reference;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& singular = svd.singularValues();
  Eigen::VectorXd inverse_singular = Eigen::VectorXd::Zero(singular.size());
  const double threshold = singular.size() > 0 ? singular(0) * kRelativeRankTolerance : 0.0;
  for (Eigen::Index k = 0; k < singular.size(); ++k) {
    if (singular(k) > threshold && singular(k) > 0) {
      inverse_singular(k) = 1.0 / singular(k);
      ++model.quadratic_rank;
    }
  }
  Eigen::MatrixXd scaled_pinv = svd.matrixV() * inverse_singular.asDiagonal() * svd.matrixU().transpose();
  if (count >= 9 && quadratic_ridge > 0.0) {
    // Ridge regression of the deviations on the modes, penalising the quadratic ones:
    // M = Q^T (Q Q^T + ridge * Y * D)^+ with D = diag(0 0 0 1 1 1 1 1 1). Per member (times Y),
    // so that a ridge means the same for a part of 9 members as for one of 150.
    Eigen::Matrix<double, 9, 9> normal = scaled * scaled.transpose();
    normal.diagonal().tail<6>().array() += quadratic_ridge * count;
    const Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>> normal_svd(normal, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto& values = normal_svd.singularValues();
    Eigen::Matrix<double, 9, 1> inverse_values = Eigen::Matrix<double, 9, 1>::Zero();
    for (int k = 0; k < 9; ++k)
      if (values(k) > values(0) * kRelativeRankTolerance && values(k) > 0) inverse_values(k) = 1.0 / values(k);
    scaled_pinv = scaled.transpose() * (normal_svd.matrixV() * inverse_values.asDiagonal() * normal_svd.matrixU().transpose());
  }
  if (count < 9) {
    // Eq. 6 needs Q0 Q0^T invertible, which fewer members than the 9 modes can never give: the
    // minimum-norm fit then puts arbitrary curvature between them (measured: up to 500 mm
    // swings inside small parts). Fit the linear modes alone instead.
    const Eigen::MatrixXd linear = scaled.topRows(3);
    const Eigen::JacobiSVD<Eigen::MatrixXd> linear_svd(linear, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd& values = linear_svd.singularValues();
    Eigen::VectorXd inverse_values = Eigen::VectorXd::Zero(values.size());
    model.quadratic_rank = 0;
    for (Eigen::Index k = 0; k < values.size(); ++k)
      if (values(k) > values(0) * kRelativeRankTolerance && values(k) > 0) {
        inverse_values(k) = 1.0 / values(k);
        ++model.quadratic_rank;
      }
    scaled_pinv.setZero();
    scaled_pinv.leftCols(3) = linear_svd.matrixV() * inverse_values.asDiagonal() * linear_svd.matrixU().transpose();
  }
  model.pseudo_inverse = scaled_pinv * row_scale.cwiseInverse().asDiagonal();  // undo the scaling
  model.reference_projection = model.local_reference * model.pseudo_inverse;

  model.local_min = model.local_reference.rowwise().minCoeff();
  model.local_max = model.local_reference.rowwise().maxCoeff();

  const double nearest = largest_nearest_member_distance(model.local_reference_points);
  model.rbf_dilation = nearest > 1e-9 ? 2.0 * nearest : 0.0;
  return model;
}

}  // namespace skinstream
