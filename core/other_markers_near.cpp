#include "core/other_markers_near.h"

#include <algorithm>
#include <limits>

namespace skinstream {

double nearest_other_expected(const FrameEstimates& frame, MarkerExpectation& expectation, int i,
                              const Vec3& p) {
  double nearest = std::numeric_limits<double>::infinity();
  for (int j : frame.missing) {
    if (frame.observed[j] || j == i || !frame.estimated[j]) continue;
    const double reach = kPrefilterReach * frame.eps1[j];
    if ((p - frame.estimate[j]).squaredNorm() > reach * reach) continue;
    Vec3 expected;
    if (!expectation.expected(j, expected, nullptr)) continue;
    const double d = (p - expected).norm();
    if (d <= frame.eps1[j]) nearest = std::min(nearest, d);
  }
  return nearest;
}

double nearest_other_on_track(const FrameEstimates& frame, MarkerExpectation& expectation, int i,
                              const Vec3& p) {
  double nearest = std::numeric_limits<double>::infinity();
  Vec3 unused;
  for (int j : frame.missing) {
    if (frame.observed[j] || j == i || frame.tracks.last_status(j) == MarkerStatus::Held) continue;
    const double d = (p - frame.tracks.prediction(j)).norm();
    if (d <= frame.eps1[j] && d < nearest && !expectation.expected(j, unused, nullptr)) nearest = d;
  }
  return nearest;
}

}  // namespace skinstream
