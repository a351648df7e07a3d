#include "core/region_pca_fit.h"

#include <algorithm>

namespace skinstream {

// Aligns the first `aligned` of world_ with mean_, then conditions the shape on the observed
// members (the first observed_count_ of world_, at slots_) as seen in that frame.
void RegionPcaFit::align_and_condition(const RegionShapeGaussian& shape, int aligned) {
  fit_rigid({world_.data(), static_cast<size_t>(aligned)}, {mean_.data(), static_cast<size_t>(aligned)}, to_region_);
  weights_.resize(3 * observed_count_);
  for (int o = 0; o < observed_count_; ++o)
    weights_.segment<3>(3 * o) = to_region_.apply(world_[o]) - shape.mean.segment<3>(3 * slots_[o]);
  lower_->triangularView<Eigen::Lower>().solveInPlace(weights_);
  lower_->triangularView<Eigen::Lower>().transpose().solveInPlace(weights_);
}

bool RegionPcaFit::factor(const RegionShapeGaussian& shape, uint32_t mask, RegionFactor& out) {
  const int count = observed_count_;
  PcaMatrix& covariance = out.lower;
  covariance.resize(3 * count, 3 * count);
  for (int a = 0; a < count; ++a)
    for (int b = 0; b < count; ++b) covariance.block<3, 3>(3 * a, 3 * b) = shape.covariance.block<3, 3>(3 * slots_[a], 3 * slots_[b]);
  covariance.diagonal().array() += shape.residual_variance;
  const Eigen::LLT<Eigen::Ref<PcaMatrix>> llt(covariance);  // in place
  out.observed_mask = llt.info() == Eigen::Success ? mask : 0;
  return out.observed_mask != 0;
}

// E[member `slot` | observed] in the region's frame: mean + C(slot, observed) weights_.
Vec3 RegionPcaFit::conditional_mean(const RegionShapeGaussian& shape, int slot) const {
  Vec3 p = shape.mean.segment<3>(3 * slot);
  for (int o = 0; o < observed_count_; ++o)
    p.noalias() += shape.covariance.block<3, 3>(3 * slot, 3 * slots_[o]) * weights_.segment<3>(3 * o);
  return p;
}

bool RegionPcaFit::estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                            Vec3& out, double& out_variance) {
  if (model.training_frames == 0) return false;
  region_gaussian_from_pca(model, from_model_);
  return estimate(from_model_, positions, observed, out, out_variance);
}

bool RegionPcaFit::estimate(const RegionShapeGaussian& shape, std::span<const Vec3> positions, std::span<const char> observed,
                            Vec3& out, double& out_variance, RegionFactor* kept, long shape_version) {
  const int size = shape.members();
  if (static_cast<int>(positions.size()) != size || static_cast<int>(observed.size()) != size) return false;
  int count = 0;
  for (int k = 1; k < size; ++k) {
    if (!observed[k]) continue;
    world_[count] = positions[k];
    mean_[count] = shape.mean.segment<3>(3 * k);
    slots_[count] = k;
    ++count;
  }
  if (count < 3) return false;
  observed_count_ = count;
  // The observed members' covariance depends only on which are observed: factored once.
  uint32_t mask = 0;
  for (int o = 0; o < count; ++o) mask |= 1u << slots_[o];
  RegionFactor& use = kept ? *kept : own_factor_;
  if (!kept || use.observed_mask != mask || use.shape_version != shape_version) {
    use.shape_version = shape_version;
    if (!factor(shape, mask, use)) return false;
  }
  lower_ = &use.lower;
  align_and_condition(shape, count);
  // Alignment and estimate depend on each other (a pose's change can look like a turn of the
  // observed part): alternate, the missing members as estimated joining the alignment after the
  // observed ones, until the estimate moves less than kConverged.
  Vec3 last = to_region_.apply_inverse(conditional_mean(shape, 0));
  for (int round = 0; round < kMaxAlignments; ++round) {
    int all = count;
    for (int k = 0; k < size; ++k) {
      if (k > 0 && observed[k]) continue;
      world_[all] = to_region_.apply_inverse(conditional_mean(shape, k));
      mean_[all] = shape.mean.segment<3>(3 * k);
      ++all;
    }
    align_and_condition(shape, all);
    const Vec3 now = to_region_.apply_inverse(conditional_mean(shape, 0));
    const bool converged = (now - last).squaredNorm() < kConverged * kConverged;
    last = now;
    if (converged) break;
  }
  out = last;
  // Conditional variance of member 0 per coordinate: (trace C_00 - |L^-1 C_o0|^2) / 3 + residual.
  cross_.resize(3 * count, 3);
  for (int o = 0; o < count; ++o) cross_.middleRows<3>(3 * o) = shape.covariance.block<3, 3>(3 * slots_[o], 0);
  lower_->triangularView<Eigen::Lower>().solveInPlace(cross_);
  const double variance =
      std::max(0.0, shape.covariance.topLeftCorner<3, 3>().trace() - cross_.squaredNorm()) / 3.0 + shape.residual_variance;
  // A pose unlike any the shape has seen shows as observed members it does not explain: their
  // miss against its estimate of them is residual^2 |weights_|^2. Its claim is then worth as
  // much less as they miss by more than its residual.
  const double miss = shape.residual_variance * shape.residual_variance * weights_.squaredNorm();
  out_variance = variance * shape.calibration * novelty_factor(miss, count, shape.residual_variance);
  return true;
}

}  // namespace skinstream
