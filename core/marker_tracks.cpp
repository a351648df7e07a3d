#include "core/marker_tracks.h"

#include <algorithm>

namespace skinstream {

MarkerTracks::MarkerTracks(int markers)
    : last_(markers, Vec3::Zero()),
      last_status_(markers, MarkerStatus::Held),
      before_last_(markers, Vec3::Zero()),
      before_last_measured_(markers, 0) {}

void MarkerTracks::advance(std::span<const Vec3> positions, std::span<const MarkerStatus> status) {
  for (size_t i = 0; i < last_.size(); ++i) {
    before_last_[i] = last_[i];
    before_last_measured_[i] = has_last_ && is_observed(last_status_[i]);
    last_[i] = positions[i];
    last_status_[i] = status[i];
  }
  has_last_ = true;
}

void MarkerTracks::reset() {
  has_last_ = false;
  std::fill(last_status_.begin(), last_status_.end(), MarkerStatus::Held);
  std::fill(before_last_measured_.begin(), before_last_measured_.end(), 0);
}

bool MarkerTracks::measured_last_two_frames(int i) const {
  return before_last_measured_[i] && is_observed(last_status_[i]);
}

Vec3 MarkerTracks::prediction(int i) const {
  if (!measured_last_two_frames(i)) return last_[i];
  return 2.0 * last_[i] - before_last_[i];
}

bool MarkerTracks::off_track(int i, const Vec3& p, double tolerance) const {
  if (!measured_last_two_frames(i)) return false;
  const double travel = (last_[i] - before_last_[i]).norm();
  return (p - prediction(i)).norm() > tolerance + travel;
}

}  // namespace skinstream
