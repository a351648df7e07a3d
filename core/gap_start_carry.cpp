#include "core/gap_start_carry.h"

#include <algorithm>
#include <cmath>

#include "core/absolute_orientation.h"

namespace skinstream {

GapStartCarry::GapStartCarry(const SubjectModel& model, double rate_hz) : model_(model) {
  const int n = model.marker_count();
  const size_t anchors = model.anchors.size();
  check_frames_ = std::max(1, static_cast<int>(std::lround(0.5 * rate_hz)));
  gap_start_known_.assign(n, 0);
  gap_start_frame_.assign(n, 0);
  gap_start_position_.assign(n, Vec3::Zero());
  gap_start_anchor_.assign(anchors, Vec3::Zero());
  gap_start_anchor_seen_.assign(anchors, 0);
  snapshot_frame_.assign(n, -1);
  snapshot_position_.assign(n, Vec3::Zero());
  snapshot_anchor_.assign(anchors, Vec3::Zero());
  snapshot_anchor_seen_.assign(anchors, 0);
  drift_.assign(n, 0.0);
  checks_.assign(n, 0);
}

void GapStartCarry::reset() {
  std::fill(gap_start_known_.begin(), gap_start_known_.end(), 0);
  std::fill(snapshot_frame_.begin(), snapshot_frame_.end(), -1);
  std::fill(drift_.begin(), drift_.end(), 0.0);
  std::fill(checks_.begin(), checks_.end(), 0);
}

void GapStartCarry::remember_gap_start(int i, long frame, std::span<const Vec3> previous,
                                       std::span<const MarkerStatus> previous_status) {
  gap_start_known_[i] = 1;
  gap_start_frame_[i] = frame;
  gap_start_position_[i] = previous[i];
  for (int k = model_.anchor_offsets[i]; k < model_.anchor_offsets[i + 1]; ++k) {
    const int a = model_.anchors[k];
    gap_start_anchor_[k] = previous[a];
    gap_start_anchor_seen_[k] = is_observed(previous_status[a]);
  }
}

// `from_position` at an earlier frame carried by the rigid motion, from then to now, of marker
// i's first kAnchors anchors seen both then and now (`from_anchors`, `from_seen`: parallel to its
// anchors). Also the fit's squared residual over them, per degree of freedom (how far they moved
// from rigid).
bool GapStartCarry::carry_rigidly(int i, const Vec3& from_position, std::span<const Vec3> from_anchors,
                                  std::span<const char> from_seen, std::span<const Vec3> positions,
                                  std::span<const char> observed, Vec3& out, double& out_residual) const {
  const int first = model_.anchor_offsets[i];
  std::array<Vec3, kAnchors> source, target;
  int count = 0;
  for (int k = first; k < model_.anchor_offsets[i + 1] && count < kAnchors; ++k) {
    const int a = model_.anchors[k];
    if (!from_seen[k - first] || !observed[a]) continue;
    source[count] = from_anchors[k - first];
    target[count] = positions[a];
    ++count;
  }
  if (count < kAnchors) return false;
  RigidTransform t;
  fit_rigid({source.data(), static_cast<size_t>(count)}, {target.data(), static_cast<size_t>(count)}, t);
  double residual = 0.0;
  for (int k = 0; k < count; ++k) residual += (t.apply(source[k]) - target[k]).squaredNorm();
  out = t.apply(from_position);
  out_residual = residual / (3 * count - 6);
  return true;
}

// The variance grows with the gap's age at the rate the carry drifted for this marker while it
// was seen, on top of the anchors' own departure from rigid; never below the marker model's
// residual.
bool GapStartCarry::carried(int i, long frame, std::span<const Vec3> positions,
                            std::span<const char> observed, Vec3& out, double& out_variance) const {
  if (!gap_start_known_[i] || checks_[i] < kWarmupChecks) return false;
  const int first = model_.anchor_offsets[i], count = model_.anchor_offsets[i + 1] - first;
  double residual = 0.0;
  if (!carry_rigidly(i, gap_start_position_[i], {&gap_start_anchor_[first], static_cast<size_t>(count)},
                     {&gap_start_anchor_seen_[first], static_cast<size_t>(count)}, positions, observed, out,
                     residual))
    return false;
  const double age = static_cast<double>(frame - gap_start_frame_[i]) + 1.0;
  out_variance = std::max(residual + drift_[i] * age * age / 3.0, model_.pca[i].residual_variance);
  return true;
}

// The drift is the carry's squared miss per frame squared, averaged over the recent checks.
void GapStartCarry::check(long frame, std::span<const Vec3> positions, std::span<const char> observed) {
  for (int i = 0; i < model_.marker_count(); ++i) {
    if (!observed[i]) continue;
    const long age = frame - snapshot_frame_[i];
    if (snapshot_frame_[i] >= 0 && age < check_frames_) continue;
    const int first = model_.anchor_offsets[i], count = model_.anchor_offsets[i + 1] - first;
    Vec3 carried;
    double residual = 0.0;
    if (snapshot_frame_[i] >= 0 &&
        carry_rigidly(i, snapshot_position_[i], {&snapshot_anchor_[first], static_cast<size_t>(count)},
                      {&snapshot_anchor_seen_[first], static_cast<size_t>(count)}, positions, observed,
                      carried, residual)) {
      const double drift = (carried - positions[i]).squaredNorm() / (static_cast<double>(age) * age);
      drift_[i] = checks_[i] == 0 ? drift : 0.5 * (drift_[i] + drift);
      ++checks_[i];
    }
    snapshot_frame_[i] = frame;
    snapshot_position_[i] = positions[i];
    for (int k = first; k < first + count; ++k) {
      snapshot_anchor_[k] = positions[model_.anchors[k]];
      snapshot_anchor_seen_[k] = observed[model_.anchors[k]];
    }
  }
}

}  // namespace skinstream
