#include "core/ring_calibration.h"

#include <algorithm>
#include <cmath>

#include "core/absolute_orientation.h"

namespace skinstream {

RingCalibration::RingCalibration(const SubjectModel& model, double rate_hz)
    : model_(model), rate_hz_(rate_hz) {
  const int n = model.marker_count();
  nominal_frames_ = std::max<long>(1, (n + kChecksPerFrame - 1) / kChecksPerFrame);
  ring_recent_.assign(model.ring.size(), RecentMiss{});
  ring_calibration_.assign(model.ring.size(), 1.0);
  checked_frame_.assign(n, -1);
  rigid_recent_.assign(n, RecentMiss{});
  rigid_calibration_.assign(n, 1.0);
}

void RingCalibration::reset() {
  std::fill(ring_recent_.begin(), ring_recent_.end(), RecentMiss{});
  std::fill(ring_calibration_.begin(), ring_calibration_.end(), 1.0);
  std::fill(checked_frame_.begin(), checked_frame_.end(), -1);
  std::fill(rigid_recent_.begin(), rigid_recent_.end(), RecentMiss{});
  std::fill(rigid_calibration_.begin(), rigid_calibration_.end(), 1.0);
  cursor_ = 0;
}

// Each check's miss and claim count for the time since the model's last check (at most the time
// between checks when every ring is seen), and what came before is forgotten over that time.
void RingCalibration::check(std::span<const Vec3> positions, std::span<const MarkerStatus> status,
                            SingleGapReconstruction& single_gaps) {
  ++frame_;
  const int n = model_.marker_count();
  for (int scanned = 0, checked = 0; scanned < n && checked < kChecksPerFrame; ++scanned) {
    const int j = cursor_;
    cursor_ = (cursor_ + 1) % n;
    const int first = model_.ring_offsets[j], ring = model_.ring_size(j);
    bool whole = status[j] == MarkerStatus::Measured && ring >= 3;
    for (int k = 0; k < ring && whole; ++k) whole = status[model_.ring[first + k]] == MarkerStatus::Measured;
    if (!whole) continue;
    ++checked;
    const long elapsed = checked_frame_[j] < 0 ? nominal_frames_ : frame_ - checked_frame_[j];
    checked_frame_[j] = frame_;
    const double forget = std::exp(-static_cast<double>(elapsed) / rate_hz_ / kMemorySeconds);
    const double seconds = static_cast<double>(std::min(elapsed, nominal_frames_)) / rate_hz_;
    // Eq. 2 on the whole ring, against the variance it claims there.
    for (int k = 0; k < ring; ++k) {
      source_[k] = model_.ring_local_reference[first + k];
      target_[k] = positions[model_.ring[first + k]];
    }
    RigidTransform t;
    fit_rigid({source_.data(), static_cast<size_t>(ring)}, {target_.data(), static_cast<size_t>(ring)}, t);
    rigid_recent_[j].add(forget, seconds, (t.translation - positions[j]).squaredNorm() / 3.0,
                         model_.pca[j].rigid_variance);
    rigid_calibration_[j] = std::max(1.0, rigid_recent_[j].ratio());
    // Every member from the others, in j's local frame.
    for (int s = 0; s < ring; ++s) {
      int count = 0;
      for (int k = 0; k < ring; ++k) {
        if (k == s) continue;
        source_[count] = positions[model_.ring[first + k]] - positions[j];
        target_[count] = model_.ring_local_reference[first + k];
        slots_[count] = k;
        ++count;
      }
      Eigen::Matrix3d r;
      fit_rotation({source_.data(), static_cast<size_t>(count)}, {target_.data(), static_cast<size_t>(count)},
                   r);
      for (int o = 0; o < count; ++o) source_[o] = r * source_[o];
      Vec3 estimate;
      single_gaps.reconstruct(j, s, {source_.data(), static_cast<size_t>(count)},
                              {slots_.data(), static_cast<size_t>(count)}, estimate);
      const int at = first + s;
      const double miss = (estimate - r * (positions[model_.ring[at]] - positions[j])).squaredNorm() / 3.0;
      ring_recent_[at].add(forget, seconds, miss, single_gaps.variance(at));
      ring_calibration_[at] = std::max(1.0, ring_recent_[at].ratio());
    }
  }
}

}  // namespace skinstream
