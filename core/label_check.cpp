#include "core/label_check.h"

#include <algorithm>
#include <cmath>

namespace skinstream {

LabelCheck::LabelCheck(const SubjectModel& model) : model_(model) { suspects_.reserve(model.marker_count()); }

void LabelCheck::find_suspects(std::span<const Vec3> points, std::span<char> observed,
                               std::span<const double> eps2, const MarkerTracks& tracks) {
  suspects_.clear();
  for (int i = 0; i < model_.marker_count(); ++i) {
    Vec3 expected;
    if (!observed[i] || tracks.last_status(i) == MarkerStatus::Held) continue;
    if (!carried_position(i, points, observed, tracks, expected)) expected = tracks.last(i);
    if ((points[i] - expected).norm() > eps2[i]) suspects_.push_back(i);
  }
  for (int i : suspects_) observed[i] = 0;
}

bool LabelCheck::carried_position(int i, std::span<const Vec3> points, std::span<const char> observed,
                                  const MarkerTracks& tracks, Vec3& out) const {
  Vec3 displacement = Vec3::Zero();
  int count = 0;
  for (int k = model_.ring_offsets[i]; k < model_.ring_offsets[i + 1]; ++k) {
    const int j = model_.ring[k];
    if (!observed[j]) continue;
    displacement += points[j] - tracks.last(j);
    ++count;
  }
  if (count < 2) return false;
  out = tracks.last(i) + displacement / count;
  return true;
}

bool LabelCheck::rejects(int i, const FrameEstimates& frame, std::span<const double> eps2,
                         MarkerExpectation& expectation) const {
  const Vec3& point = frame.points[i];
  Vec3 own;
  double own_variance = 0.0;
  const bool has_own = expectation.expected(i, own, &own_variance);
  if (!has_own)
    return explained_by_another(i, (point - frame.tracks.prediction(i)).norm(), frame, expectation) ||
           frame.tracks.off_track(i, point, eps2[i]);
  const double own_distance = (point - own).norm();
  const bool own_confident = own_distance * own_distance > kConfidentMiss * own_variance;
  return (own_distance > eps2[i] || own_confident) &&
         (explained_by_another(i, own_distance, frame, expectation) ||
          (own_distance > eps2[i] && frame.tracks.off_track(i, point, eps2[i])));
}

bool LabelCheck::explained_by_another(int i, double own_distance, const FrameEstimates& frame,
                                      MarkerExpectation& expectation) const {
  const Vec3& point = frame.points[i];
  const double nearest = std::min(nearest_other_expected(frame, expectation, i, point),
                                  nearest_other_on_track(frame, expectation, i, point));
  return std::isfinite(nearest) && nearest <= 0.5 * own_distance;
}

}  // namespace skinstream
