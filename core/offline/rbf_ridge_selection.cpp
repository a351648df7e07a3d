#include "core/offline/rbf_ridge_selection.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/deform/part_deformation.h"
#include "core/deform/rbf_kernel.h"
#include "core/offline/training_frames.h"

namespace skinstream {

std::vector<double> rbf_ridge_candidates() {
  std::vector<double> ridges{0.0};
  for (int k = -20; k <= 0; ++k) ridges.push_back(std::pow(10.0, k / 4.0));  // 4 per decade, 1e-5 .. 1
  return ridges;
}

std::vector<double> leave_one_out_squared_errors(const Eigen::Matrix3Xd& centres, const Eigen::MatrixX3d& residuals,
                                                 double dilation, std::span<const double> ridges) {
  const int count = static_cast<int>(centres.cols());
  Eigen::MatrixXd kernel(count, count);
  fill_rbf_kernel(centres.transpose(), dilation, kernel);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(kernel);
  const Eigen::MatrixXd& v = eigen.eigenvectors();
  const Eigen::VectorXd& mu = eigen.eigenvalues();
  const Eigen::MatrixXd projected = v.transpose() * residuals;  // V^T r
  const Eigen::MatrixXd v_squared = v.array().square();
  const double tiny = 1e-12 * std::max(mu.cwiseAbs().maxCoeff(), 1.0);

  std::vector<double> scores;
  for (double ridge : ridges) {
    const Eigen::VectorXd shifted = mu.array() + ridge;
    if ((shifted.array().abs() < tiny).any()) {
      scores.push_back(std::numeric_limits<double>::infinity());
      continue;
    }
    const Eigen::VectorXd inverse = shifted.cwiseInverse();
    const Eigen::MatrixXd c = v * (inverse.asDiagonal() * projected);  // A^-1 r
    const Eigen::VectorXd diagonal = v_squared * inverse;               // (A^-1)_ii
    double sum = 0.0;
    for (int i = 0; i < count; ++i) sum += c.row(i).squaredNorm() / (diagonal[i] * diagonal[i]);
    scores.push_back(std::isfinite(sum) ? sum : std::numeric_limits<double>::infinity());
  }
  return scores;
}

RidgeChoice choose_rbf_ridge(const PartModel& part, std::span<const int> member_markers, std::span<const Vec3> training,
                             int frame_count, int marker_count, int sample_frames,
                             std::span<const RigidTransform> segment_motions) {
  check_training_take("choose_rbf_ridge", training, frame_count, marker_count);
  if (!segment_motions.empty() && static_cast<int>(segment_motions.size()) != frame_count)
    throw std::invalid_argument("choose_rbf_ridge: one segment motion per training frame is needed");
  if (static_cast<int>(member_markers.size()) != part.member_count())
    throw std::invalid_argument("choose_rbf_ridge: member list does not match the part");
  RidgeChoice choice;
  if (part.rbf_dilation <= 0.0 || part.member_count() < 2) return choice;

  const std::vector<double> ridges = rbf_ridge_candidates();
  std::vector<double> total(ridges.size(), 0.0);
  PartDeformer fit(part, DeformationMode::Quadratic);  // eq. 6: the centres and residuals of eq. 7
  choice.frames = for_each_training_frame(
      member_markers, training, frame_count, marker_count, sample_frames,
      [&](int frame, const std::vector<Vec3>& members) {
        const bool solved = segment_motions.empty() ? fit.solve(members) : fit.solve(members, segment_motions[frame]);
        if (!solved) throw std::invalid_argument("choose_rbf_ridge: a training frame misses a member");
        const Eigen::MatrixX3d residuals = (fit.local_positions() - fit.rbf_centres()).transpose();
        const std::vector<double> scores =
            leave_one_out_squared_errors(fit.rbf_centres(), residuals, part.rbf_dilation, ridges);
        for (size_t k = 0; k < ridges.size(); ++k) total[k] += scores[k];
      });
  size_t best = 0;
  for (size_t k = 1; k < ridges.size(); ++k)
    if (total[k] < total[best]) best = k;
  const double samples = static_cast<double>(choice.frames) * part.member_count();
  choice.ridge = ridges[best];
  choice.loo_rms_mm = std::sqrt(total[best] / samples);
  choice.loo_rms_exact_mm = std::sqrt(total[0] / samples);
  return choice;
}

}  // namespace skinstream
