#include "core/offline/quadratic_ridge_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/deform/part_deformation.h"
#include "core/deform/part_model.h"
#include "core/offline/training_frames.h"

namespace skinstream {

std::vector<double> quadratic_ridge_candidates() {
  std::vector<double> ridges{0.0};
  for (int k = -8; k <= 8; ++k) ridges.push_back(std::pow(10.0, k / 2.0));  // 2 per decade, 1e-4 .. 1e4
  return ridges;
}

QuadraticRidgeChoice choose_quadratic_ridge(const std::vector<Vec3>& reference, std::span<const int> member_markers,
                                            std::span<const Vec3> training, int frame_count, int marker_count,
                                            int sample_frames, std::span<const RigidTransform> segment_motions) {
  check_training_take("choose_quadratic_ridge", training, frame_count, marker_count);
  if (!segment_motions.empty() && static_cast<int>(segment_motions.size()) != frame_count)
    throw std::invalid_argument("choose_quadratic_ridge: one segment motion per training frame is needed");
  if (member_markers.size() != reference.size())
    throw std::invalid_argument("choose_quadratic_ridge: member list does not match the part");
  QuadraticRidgeChoice choice;
  const int count = static_cast<int>(reference.size());
  if (count < 9) return choice;  // the linear modes only, whatever the ridge

  // The members' deviations from the reference in the part's frame after the rigid fit, one
  // 3 x Y block per sampled frame: what eq. 6 fits.
  const PartModel exact = build_part_model(reference);
  PartDeformer rigid(exact, DeformationMode::Rigid);
  std::vector<Eigen::Matrix3Xd> deviations;
  const int frames = for_each_training_frame(
      member_markers, training, frame_count, marker_count, sample_frames,
      [&](int frame, const std::vector<Vec3>& members) {
        const bool solved = segment_motions.empty() ? rigid.solve(members) : rigid.solve(members, segment_motions[frame]);
        if (!solved) throw std::invalid_argument("choose_quadratic_ridge: a training frame misses a member");
        deviations.push_back(rigid.local_positions() - exact.local_reference);
      });
  choice.frames = frames;

  const std::vector<double> ridges = quadratic_ridge_candidates();
  std::vector<double> total(ridges.size(), 0.0);
  for (size_t k = 0; k < ridges.size(); ++k) {
    const PartModel part = ridges[k] == 0.0 ? exact : build_part_model(reference, ridges[k]);
    const Eigen::MatrixXd hat = part.pseudo_inverse * part.quadratic_reference;  // H = M Q0
    const Eigen::VectorXd left_out = Eigen::VectorXd::Ones(count) - hat.diagonal();
    if ((left_out.array() < 1e-9).any()) {  // a member the fit interpolates: no prediction of it
      total[k] = std::numeric_limits<double>::infinity();
      continue;
    }
    const Eigen::ArrayXd weight = left_out.array().square().inverse();
    for (const Eigen::Matrix3Xd& d : deviations) {
      const Eigen::Matrix3Xd residual = d - d * hat;
      total[k] += (residual.colwise().squaredNorm().transpose().array() * weight).sum();
    }
  }
  size_t best = 0;
  for (size_t k = 1; k < ridges.size(); ++k)
    if (total[k] < total[best]) best = k;
  const double samples = static_cast<double>(frames) * count;
  choice.ridge = ridges[best];
  choice.loo_rms_mm = std::sqrt(total[best] / samples);
  choice.loo_rms_exact_mm = std::sqrt(total[0] / samples);
  return choice;
}

}  // namespace skinstream
