#pragma once
// Step 1 of the gap filler (gap_filler.h): which labelled points to doubt, and which of the
// doubted ones to take as unlabelled.
//
// A correctly labelled point moves with its neighbours: within a frame its offset from them
// changes by millimetres, while a swapped or mislabelled point is off by about the marker
// spacing. So a labelled point farther than eps2 from where its marker was carried by its
// one-ring is suspect, and held back from the estimates until judged. Being off is not proof: a
// fast limb at a low frame rate, or the end of a gap whose estimate was poor, puts a true
// measurement beyond eps2 too, and so does a rejected point that another marker took last frame
// and carried along. So a suspect is judged against the estimates made this frame from the other
// markers, and taken as unlabelled only on strong evidence.

#include <span>
#include <vector>

#include "core/capture.h"
#include "core/marker_tracks.h"
#include "core/other_markers_near.h"
#include "core/subject_model.h"

namespace skinstream {

class LabelCheck {
 public:
  explicit LabelCheck(const SubjectModel& model);

  // Lists the labelled points (observed, with a position last frame) farther than eps2 from where
  // their marker was carried by its observed one-ring since the last frame, or, with fewer than
  // two ring members seen (skin touching skin, a limb hidden), from its last position: a label
  // that jumps by more than eps2 in one frame is just as suspect. Holds them back (observed = 0).
  void find_suspects(std::span<const Vec3> points, std::span<char> observed, std::span<const double> eps2,
                     const MarkerTracks& tracks);
  std::span<const int> suspects() const { return suspects_; }
  void clear() { suspects_.clear(); }

  // Whether suspect i is taken as unlabelled. It stands when its own expected position agrees
  // (within eps2 and within four of its calibrated standard deviations). It is taken when another
  // marker explains it clearly better (a swap, or skin touching skin), or when its own estimate
  // disagrees by more than eps2 and it left its own track as well (measured in the last two
  // frames and now off where its velocity takes it): a point that keeps to its track is the
  // marker the capture system was following, whatever its neighbourhood's estimate says. With no
  // estimate of its own, its track is the evidence left. Otherwise the measurement stands.
  bool rejects(int i, const FrameEstimates& frame, std::span<const double> eps2,
               MarkerExpectation& expectation) const;

 private:
  // Where marker i would be now had it moved with its neighbours since the last frame: its last
  // position carried by the mean displacement of its observed one-ring. False with fewer than
  // two of them.
  bool carried_position(int i, std::span<const Vec3> points, std::span<const char> observed,
                        const MarkerTracks& tracks, Vec3& out) const;
  // Whether another missing (or suspect) marker is expected within eps1 of i's labelled point,
  // at most half as far from it as `own_distance`: by its estimate, or, where it has none (a
  // hidden patch, every label in it suspect at once), by its own track: two labels swapped on
  // returning from a gap are each near where the other one was.
  bool explained_by_another(int i, double own_distance, const FrameEstimates& frame,
                            MarkerExpectation& expectation) const;

  // A labelled point this many variances (squared distance over the calibrated predictive
  // variance) from its own estimate is confidently not where the marker is expected.
  static constexpr double kConfidentMiss = 16.0;

  const SubjectModel& model_;
  std::vector<int> suspects_;
};

}  // namespace skinstream
