#pragma once
// Each marker's own track over the last two frames: where the gap filler put it last frame
// (measured, relabelled or estimated), with which status, and whether it was measured the frame
// before too. What a labelled point is judged against when its neighbourhood cannot judge it:
// a point that keeps to its marker's track is the marker the capture system was following, and
// one that jumps off it is a swap or a ghost (GapFiller's label check and relabelling).
//
// Everything is sized in the constructor; nothing allocates after it.

#include <span>
#include <vector>

#include "core/capture.h"
#include "core/marker_status.h"

namespace skinstream {

class MarkerTracks {
 public:
  explicit MarkerTracks(int markers);

  // After a frame: its output becomes the last frame, and the last frame the one before.
  void advance(std::span<const Vec3> positions, std::span<const MarkerStatus> status);
  // Forget every track (a new take, a source reconnected): no marker has a last frame.
  void reset();

  // Whether any frame came since the construction or the last reset().
  bool has_last() const { return has_last_; }
  const Vec3& last(int i) const { return last_[i]; }
  MarkerStatus last_status(int i) const { return last_status_[i]; }
  // One per marker: what GapStartCarry keeps at the start of a gap.
  std::span<const Vec3> last_positions() const { return last_; }
  std::span<const MarkerStatus> last_statuses() const { return last_status_; }
  // A relabel revoked in this frame: the marker's last frame counts as estimated from then on,
  // so that nothing is carried on from the fragment it was given.
  void take_last_as_estimated(int i) { last_status_[i] = MarkerStatus::FilledRigid; }

  // Whether marker i was measured (or relabelled) in each of the last two frames: then it has a
  // velocity of its own.
  bool measured_last_two_frames(int i) const;
  // Where marker i's own motion takes it this frame: its last position moved on by its last
  // frame's velocity when it was measured in the last two frames, else its last position (its
  // estimate, during a gap).
  Vec3 prediction(int i) const;
  // Whether point p, for marker i measured in the last two frames, is farther from where its own
  // velocity takes it than `tolerance` plus a frame's travel: a label that jumps off its track,
  // where a fast limb at a low frame rate stays near it (a serve's hand: 240 mm a frame at 50 Hz).
  bool off_track(int i, const Vec3& p, double tolerance) const;

 private:
  bool has_last_ = false;
  std::vector<Vec3> last_;
  std::vector<MarkerStatus> last_status_;
  std::vector<Vec3> before_last_;
  std::vector<char> before_last_measured_;
};

}  // namespace skinstream
