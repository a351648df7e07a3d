#pragma once
// Which other missing marker a free or doubted point could be: the question behind both the label
// check (label_check.h: is a labelled point another marker's?) and eq. 3's ambiguity test (the
// gap filler's relabelling: may a free point be taken for this marker?). Any marker may be the
// other, not only a neighbour: skin that touches is rarely neighbouring on the marker surface.

#include <span>

#include "core/capture.h"
#include "core/marker_tracks.h"

namespace skinstream {

// Where the gap filler expects marker j this frame from the other markers alone (its PCA and
// eq. 2 estimates fused), with the variance it claims when asked for (may be null); false when it
// has no estimate. An interface so that the filler answers it from its lazily solved models, and
// a test from a table.
class MarkerExpectation {
 public:
  virtual bool expected(int marker, Vec3& out, double* out_variance) = 0;

 protected:
  ~MarkerExpectation() = default;
};

// What the filler knows this frame, as views of its own buffers: read as they stand at each call.
struct FrameEstimates {
  std::span<const Vec3> points;     // this frame's labelled (and taken) points; others: anything
  std::span<const char> observed;   // which markers count as measured right now
  std::span<const int> missing;     // the markers that had no measurement when the estimates were made
  std::span<const char> estimated;  // which have an eq. 2 estimate
  std::span<const Vec3> estimate;   // that estimate
  std::span<const double> eps1;     // eq. 3's taking distance per marker (alpha1 * neighbour distance)
  const MarkerTracks& tracks;
};

// In eps1: how far from a marker's eq. 2 estimate a point may be and still be within eps1 of its
// fused estimate. The eq. 2 errors are a fraction of eps1, so looking farther only costs estimates.
inline constexpr double kPrefilterReach = 3.0;

// The distance from point p to the nearest expected position of another missing marker (not i)
// that is within eps1 of it (infinity: none).
double nearest_other_expected(const FrameEstimates& frame, MarkerExpectation& expectation, int i,
                              const Vec3& p);

// The distance from point p to the track prediction (marker_tracks.h) of the nearest other
// missing marker (not i) that has no estimate this frame and a position last frame, within eps1
// (infinity: none): where a whole patch is hidden, each marker's own track stands in for it.
double nearest_other_on_track(const FrameEstimates& frame, MarkerExpectation& expectation, int i,
                              const Vec3& p);

}  // namespace skinstream
