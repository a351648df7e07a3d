#include "core/region_pca_fit.h"

#include <algorithm>

namespace skinstream {

// Aligns the first `aligned` of world_ with mean_, then fits the coefficients to the first
// `fitted` (the observed members, at slots_).
bool RegionPcaFit::align_and_fit(const MarkerPcaModel& model, int aligned, int fitted) {
  fit_rigid({world_.data(), static_cast<size_t>(aligned)}, {mean_.data(), static_cast<size_t>(aligned)}, to_region_);
  for (int o = 0; o < fitted; ++o) local_[o] = to_region_.apply(world_[o]);
  return fit_.fit(model, {slots_.data(), static_cast<size_t>(fitted)}, {local_.data(), static_cast<size_t>(fitted)});
}

bool RegionPcaFit::estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                            Vec3& out, double& out_variance) {
  const int size = static_cast<int>(model.mean.size() / 3);
  if (model.training_frames == 0 || static_cast<int>(positions.size()) != size || static_cast<int>(observed.size()) != size)
    return false;
  int count = 0;
  for (int k = 1; k < size; ++k) {
    if (!observed[k]) continue;
    world_[count] = positions[k];
    mean_[count] = model.mean.segment<3>(3 * k);
    slots_[count] = k;
    ++count;
  }
  if (count < 3 || !align_and_fit(model, count, count)) return false;
  // Alignment and coefficients depend on each other (a pose's change can look like a turn of the
  // observed part): alternate, the missing members as reconstructed joining the alignment after
  // the observed ones, until the estimate moves less than kConverged.
  Vec3 last = to_region_.apply_inverse(fit_.reconstruct(model, 0));
  for (int round = 0; round < kMaxAlignments; ++round) {
    int all = count;
    for (int k = 0; k < size; ++k) {
      if (k > 0 && observed[k]) continue;
      world_[all] = to_region_.apply_inverse(fit_.reconstruct(model, k));
      mean_[all] = model.mean.segment<3>(3 * k);
      ++all;
    }
    if (!align_and_fit(model, all, count)) return false;
    const Vec3 now = to_region_.apply_inverse(fit_.reconstruct(model, 0));
    const bool converged = (now - last).squaredNorm() < kConverged * kConverged;
    last = now;
    if (converged) break;
  }
  out = to_region_.apply_inverse(fit_.reconstruct(model, 0));
  // A pose unlike any in training shows as observed members the model does not fit: its claim
  // is then worth as much less as they miss by more than its residual.
  double miss = 0.0;
  for (int o = 0; o < count; ++o) miss += (local_[o] - fit_.reconstruct(model, slots_[o])).squaredNorm();
  const double novelty = std::max(1.0, miss / (3.0 * count * model.residual_variance));
  out_variance = fit_.predictive_variance(model, 0) * model.slot_calibration(0) * novelty;
  return true;
}

}  // namespace skinstream
