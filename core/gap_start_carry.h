#pragma once
// During a gap, a marker's last measurement carried by the rigid motion of its steadiest anchors
// (model.anchors) since the gap started: one more opinion of where it is (beyond the paper). Over
// a long gap this does not drift as a chain of frame-to-frame motions does, and where the marker
// sits on a rigid segment with its anchors (a head, a pelvis, a foot) it is nearly exact, while a
// neighbourhood spanning a joint is not. Which one a marker has is learned while it is seen: every
// half second the same carry is tried on it from a snapshot of then, and how fast it drifted
// grows the carry's variance with the gap's age. No opinion before two seconds of such checks:
// one half-second check says little about a joint.
//
// Everything is sized in the constructor; nothing allocates after it.

#include <array>
#include <span>
#include <vector>

#include "core/marker_status.h"
#include "core/subject_model.h"

namespace skinstream {

class GapStartCarry {
 public:
  static constexpr int kAnchors = 3;       // the steadiest anchors seen both then and now
  static constexpr int kWarmupChecks = 4;  // checks before a marker's carry is trusted

  GapStartCarry(const SubjectModel& model, double rate_hz);

  // At the first frame of marker i's gap (`frame`): where it and its anchors were the frame
  // before (`previous`, `previous_status`: one per subject marker).
  void remember_gap_start(int i, long frame, std::span<const Vec3> previous,
                          std::span<const MarkerStatus> previous_status);
  // The frame marker i's last gap started (what the gap-start continuity ages with).
  long gap_start_frame(int i) const { return gap_start_frame_[i]; }
  // Marker i's position at gap start carried to now by its anchors (`positions`, `observed`:
  // one per subject marker, observed = measured or relabelled now), and the carry's variance per
  // coordinate (mm^2). False before its drift is known or with fewer than kAnchors anchors seen
  // both then and now.
  bool carried(int i, long frame, std::span<const Vec3> positions, std::span<const char> observed, Vec3& out,
               double& out_variance) const;
  // After each frame: every half second, each marker observed now is compared with the carry
  // from its last snapshot, and a new snapshot is taken.
  void check(long frame, std::span<const Vec3> positions, std::span<const char> observed);
  // The squared miss per frame squared of the recent checks (mm^2 / frame^2), and how many
  // checks it rests on.
  double drift(int i) const { return drift_[i]; }
  int checks(int i) const { return checks_[i]; }
  void reset();  // forget every gap start, snapshot and drift

 private:
  bool carry_rigidly(int i, const Vec3& from_position, std::span<const Vec3> from_anchors,
                     std::span<const char> from_seen, std::span<const Vec3> positions,
                     std::span<const char> observed, Vec3& out, double& out_residual) const;

  const SubjectModel& model_;
  int check_frames_ = 1;  // half a second
  // At the start of each marker's gap: its last position and its anchors' (parallel to
  // model.anchors; usable where the anchor was measured or relabelled then).
  std::vector<char> gap_start_known_;
  std::vector<long> gap_start_frame_;
  std::vector<Vec3> gap_start_position_;
  std::vector<Vec3> gap_start_anchor_;
  std::vector<char> gap_start_anchor_seen_;
  // The same at each marker's last check while it was seen.
  std::vector<long> snapshot_frame_;  // -1: none yet
  std::vector<Vec3> snapshot_position_;
  std::vector<Vec3> snapshot_anchor_;
  std::vector<char> snapshot_anchor_seen_;
  std::vector<double> drift_;
  std::vector<int> checks_;
};

}  // namespace skinstream
