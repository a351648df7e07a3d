#include "core/region_online_statistics.h"

#include <algorithm>
#include <cmath>

#include "core/absolute_orientation.h"

namespace skinstream {

RegionOnlineStatistics::RegionOnlineStatistics(const SubjectModel& model, const RegionLearningOptions& options)
    : model_(model), options_(options) {
  const int n = model.has_regions() ? model.marker_count() : 0;
  for (int i = 0; i < n; ++i) {
    Region r;
    r.first = model.region_offsets[i];
    r.size = model.region_offsets[i + 1] - r.first;
    r.mean_at = offline_mean_.size();
    r.matrix_at = offline_covariance_.size();
    region_gaussian_from_pca(model.region_pca[i], blend_);
    offline_mean_.insert(offline_mean_.end(), blend_.mean.data(), blend_.mean.data() + blend_.mean.size());
    offline_covariance_.insert(offline_covariance_.end(), blend_.covariance.data(),
                               blend_.covariance.data() + blend_.covariance.size());
    regions_.push_back(r);
  }
  online_mean_.assign(offline_mean_.size(), 0.0);
  scatter_.assign(offline_covariance_.size(), 0.0);
  nominal_frames_ = std::max<long>(1, (n + options_.updates_per_frame - 1) / std::max(1, options_.updates_per_frame));
  left_out_.fill(1);
  left_out_[0] = left_out_[1] = left_out_[2] = 0;
  aligned_.resize(3 * SubjectModel::kMaxRing);
}

void RegionOnlineStatistics::reset() {
  for (Region& r : regions_) r = Region{r.first, r.size, r.mean_at, r.matrix_at};
  std::fill(online_mean_.begin(), online_mean_.end(), 0.0);
  std::fill(scatter_.begin(), scatter_.end(), 0.0);
  frame_ = 0;
  cursor_ = 0;
}

void RegionOnlineStatistics::learn(std::span<const Vec3> positions, std::span<const MarkerStatus> status) {
  ++frame_;
  const int n = static_cast<int>(regions_.size());
  int updates = 0;
  for (int scanned = 0; scanned < n && updates < options_.updates_per_frame; ++scanned) {
    const int i = cursor_;
    cursor_ = (cursor_ + 1) % n;
    if (model_.region_pca[i].training_frames == 0) continue;
    const Region& r = regions_[i];
    bool whole = true;
    for (int k = 0; k < r.size && whole; ++k) whole = status[model_.region[r.first + k]] == MarkerStatus::Measured;
    if (!whole) continue;
    learn_region(i, positions);
    ++updates;
  }
}

void RegionOnlineStatistics::learn_region(int i, std::span<const Vec3> positions) {
  Region& r = regions_[i];
  const int dims = 3 * r.size;
  for (int k = 0; k < r.size; ++k) {
    shape_[k] = positions[model_.region[r.first + k]];
    reference_[k] = Eigen::Map<const Vec3>(&offline_mean_[r.mean_at + 3 * k]);
  }
  RigidTransform to_region;
  fit_rigid({shape_.data(), static_cast<size_t>(r.size)}, {reference_.data(), static_cast<size_t>(r.size)}, to_region);
  aligned_.resize(dims);
  for (int k = 0; k < r.size; ++k) aligned_.segment<3>(3 * k) = to_region.apply(shape_[k]);

  // Prequential calibration: the blend as it stands, tried on this frame before learning from it.
  double squared_miss = 0.0, claimed = 0.0;
  blended(i);
  blend_.calibration = 1.0;
  Vec3 estimate;
  double variance = 0.0;
  const bool tried = fit_.estimate(blend_, {shape_.data(), static_cast<size_t>(r.size)},
                                   {left_out_.data(), static_cast<size_t>(r.size)}, estimate, variance);
  if (tried) {
    squared_miss = (estimate - shape_[0]).squaredNorm() / 3.0;
    claimed = variance;
  }

  // Exponential forgetting in time; one frame stands for at most the time between updates when
  // every region is seen (a region seen again after a gap is one sample, not the gap's worth).
  const long elapsed = r.learned_frame < 0 ? nominal_frames_ : frame_ - r.learned_frame;
  r.learned_frame = frame_;
  ++r.updates;
  const double decay = std::exp(-static_cast<double>(elapsed) / options_.rate_hz / options_.memory_seconds);
  const double seconds = static_cast<double>(std::min(elapsed, nominal_frames_)) / options_.rate_hz;
  r.evidence = decay * r.evidence + seconds;
  if (tried) {
    const double forget = std::exp(-static_cast<double>(elapsed) / options_.rate_hz / options_.calibration_memory_seconds);
    r.recent.add(forget, seconds, squared_miss, claimed);
  }
  // Weighted Welford: mean += (s / W) delta; scatter = decay scatter + s (1 - s / W) delta delta^T.
  Eigen::Map<Eigen::VectorXd> mean(&online_mean_[r.mean_at], dims);
  Eigen::Map<Eigen::MatrixXd> scatter(&scatter_[r.matrix_at], dims, dims);
  const double share = seconds / r.evidence;
  if (share >= 1.0) mean = aligned_;  // the first sample (or all before it forgotten)
  PcaVector& delta = aligned_;
  delta -= mean;
  mean += share * delta;
  scatter *= decay;
  scatter.noalias() += (seconds * (1.0 - share)) * delta * delta.transpose();
}

double RegionOnlineStatistics::calibration(int i) const {
  const Region& r = regions_[i];
  const double offline = model_.region_pca[i].slot_calibration(0);
  if (!r.recent.any()) return std::max(1.0, offline);
  const double online = r.recent.ratio(), w = weight(r);
  return std::max({1.0, (1.0 - w) * offline + w * online, online});
}

const RegionShapeGaussian& RegionOnlineStatistics::blended(int i) {
  const Region& r = regions_[i];
  const int dims = 3 * r.size;
  const double w = weight(r);
  const Eigen::Map<const Eigen::VectorXd> offline_mean(&offline_mean_[r.mean_at], dims), online_mean(&online_mean_[r.mean_at], dims);
  const Eigen::Map<const Eigen::MatrixXd> offline_covariance(&offline_covariance_[r.matrix_at], dims, dims);
  const Eigen::Map<const Eigen::MatrixXd> scatter(&scatter_[r.matrix_at], dims, dims);
  blend_.residual_variance = model_.region_pca[i].residual_variance;
  blend_.calibration = calibration(i);
  if (w <= 0.0) {
    blend_.mean = offline_mean;
    blend_.covariance = offline_covariance;
    return blend_;
  }
  blend_.mean = (1.0 - w) * offline_mean + w * online_mean;
  const PcaVector difference = online_mean - offline_mean;
  blend_.covariance = (1.0 - w) * offline_covariance + (w / r.evidence) * scatter;
  blend_.covariance.noalias() += (w * (1.0 - w)) * difference * difference.transpose();
  return blend_;
}

}  // namespace skinstream
