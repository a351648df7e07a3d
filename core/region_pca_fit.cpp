#include "core/region_pca_fit.h"

namespace skinstream {

// Aligns the first `aligned` of world_ with mean_, then conditions the shape on the observed
// members (the first solve.observed of world_) as seen in that frame: hidden_.
void RegionPcaFit::align_and_condition(const RegionSolve& solve, int aligned) {
  fit_rigid({world_.data(), static_cast<size_t>(aligned)}, {mean_.data(), static_cast<size_t>(aligned)}, to_region_);
  for (int o = 0; o < solve.observed; ++o)
    deviation_.segment<3>(3 * o) = to_region_.apply(world_[o]) - mean_[o];
  for (int h = 0; h < solve.hidden; ++h)
    hidden_[h] = solve.mean.segment<3>(3 * solve.hidden_slots[h]) + solve.gain.middleCols<3>(3 * h).transpose() * deviation_;
}

bool RegionPcaFit::estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                            Vec3& out, double& out_variance) {
  if (model.training_frames == 0) return false;
  region_gaussian_from_pca(model, from_model_);
  return estimate(from_model_, positions, observed, out, out_variance);
}

bool RegionPcaFit::estimate(const RegionShapeGaussian& shape, std::span<const Vec3> positions, std::span<const char> observed,
                            Vec3& out, double& out_variance) {
  const int size = shape.members();
  if (static_cast<int>(positions.size()) != size || static_cast<int>(observed.size()) != size) return false;
  if (!prepare_region_solve(shape, region_observed_mask(observed), 0, own_solve_)) return false;
  estimate(own_solve_, positions, out, out_variance);
  return true;
}

void RegionPcaFit::estimate(const RegionSolve& solve, std::span<const Vec3> positions, Vec3& out, double& out_variance) {
  const int count = solve.observed;
  for (int o = 0; o < count; ++o) {
    world_[o] = positions[solve.observed_slots[o]];
    mean_[o] = solve.mean.segment<3>(3 * solve.observed_slots[o]);
  }
  for (int h = 0; h < solve.hidden; ++h) mean_[count + h] = solve.mean.segment<3>(3 * solve.hidden_slots[h]);
  deviation_.resize(3 * count);
  align_and_condition(solve, count);
  // Alignment and estimate depend on each other (a pose's change can look like a turn of the
  // observed part): alternate, the hidden members as estimated joining the alignment after the
  // observed ones, until the estimate moves less than kConverged.
  Vec3 last = to_region_.apply_inverse(hidden_[0]);
  for (int round = 0; round < kMaxAlignments; ++round) {
    for (int h = 0; h < solve.hidden; ++h) world_[count + h] = to_region_.apply_inverse(hidden_[h]);
    align_and_condition(solve, count + solve.hidden);
    const Vec3 now = to_region_.apply_inverse(hidden_[0]);
    const bool converged = (now - last).squaredNorm() < kConverged * kConverged;
    last = now;
    if (converged) break;
  }
  out = last;
  // A pose unlike any the shape has seen shows as observed members it does not explain: their
  // miss against its estimate of them is residual^2 |(L L^T)^-1 deviation|^2. Its claim is then
  // worth as much less as they miss by more than its residual.
  solve.lower.triangularView<Eigen::Lower>().solveInPlace(deviation_);
  solve.lower.triangularView<Eigen::Lower>().transpose().solveInPlace(deviation_);
  const double miss = solve.residual_variance * solve.residual_variance * deviation_.squaredNorm();
  out_variance = solve.variance * solve.calibration * novelty_factor(miss, count, solve.residual_variance);
}

}  // namespace skinstream
