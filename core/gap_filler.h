#pragma once
// The online, causal per-frame job of section 4.2-4.3: takes one frame of labelled points
// (NaN = missing) and unlabelled points, and returns every marker of the subject.
//
//   1. Label check (label_check.h): a labelled point that did not move with its one-ring since
//      the last frame (off by more than eps2) is suspect: so swapped and mislabelled fragments look,
//      but also a true measurement after a gap whose estimate was poor (with its ring unseen,
//      against its last position). It is treated as unlabelled only on strong evidence, judged
//      against this frame's estimates from the other markers: any missing marker explains it
//      clearly better while its own confident estimate disagrees (a swap, or skin touching
//      skin; with no estimates, the markers' own tracks), or its neighbourhood's estimate
//      disagrees and it left its own track (velocity prediction). Otherwise the measurement
//      stands.
//   2. Rigid estimates (eq. 2, Horn), greedy: the missing marker with the most available
//      neighbours first, reusing earlier estimates.
//   3. Relabelling: a tracked fragment stays with its marker while within eps2 (alpha2) of
//      where the marker is expected (its best estimate from the neighbours, step 4's fusion);
//      a new one is taken when within eps1 (alpha1) of it (eq. 3) and no other missing marker is
//      expected within twice that distance of it (by its estimate, else by its own track:
//      ambiguous points wait), closest pairs first, in up to three rounds, estimates redone
//      after each with the points taken. With `confirm_frames` a new relabel must pass that
//      test again each frame of its probation, else it is revoked (FrameOutput::revoked).
//   4. PCA fill: every observed neighbour's PCA model reconstructs the missing marker from that
//      neighbour's observed one-ring (regularised least squares on the coefficients); the
//      estimates are averaged, each weighted by the inverse of its predictive variance
//      (calibrated on the training take), together with the rigid estimate weighed likewise
//      (its members' departure from rigid, and the variance of any member the chain only
//      estimated, through each member's leverage on the fit: rigid_fit_leverage.h).
//      Each variance is grown by its model's misfit to what it was fitted to this frame
//      (novelty_factor, pca_fit.h): a pose training never showed makes its claim worth less.
//      And each is scaled by how much it lately missed: a few models a frame, where the marker
//      and its whole ring are measured, estimate every member (and eq. 2 the marker) from the
//      rest, and the miss over the variance claimed (recent frames counting most), never below
//      one, scales the claim (ring_calibration.h): a ring that spans the two feet, steady while the
//      subject stood in training, is no judge of either foot in a walk.
//      Without one, the rigid estimate; without that, held relative to the marker's anchors.
//      The marker's regional PCA (region_pca_fit.h), aligned on whichever members of its region
//      are seen, joins as one more opinion weighed by its calibrated variance: it holds where the
//      marker's own neighbourhood is gone. The regions learn from the frames in which they are
//      measured whole (region_online_statistics.h).
//   5. Continuity: at the start of a gap, the difference between where the marker's last
//      measurement moved with its neighbours (those seen in both frames) and the estimate is
//      kept in the local frame and decays over `continuity_seconds`, so a gap does not start
//      with a jump.
//
// All buffers are sized in the constructor; run() allocates nothing.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/gap_start_carry.h"
#include "core/label_check.h"
#include "core/marker_status.h"
#include "core/marker_tracks.h"
#include "core/other_markers_near.h"
#include "core/pca_fit.h"
#include "core/region_online_statistics.h"
#include "core/region_pca_fit.h"
#include "core/ring_calibration.h"
#include "core/single_gap_reconstruction.h"
#include "core/subject_model.h"

namespace skinstream {

struct GapFillerOptions {
  double rate_hz = 120.0;
  double continuity_seconds = 1.0;  // 0 turns the gap-start continuity off
  bool use_pca = true;              // false: eq. 2 estimates only
  // Average the neighbours' PCA estimates weighted by each one's predictive variance (true),
  // or plainly as the paper does (false).
  bool weight_by_variance = true;
  bool fuse_rigid = true;  // with weighting: the rigid estimate (eq. 2) is one more weighed opinion
  // With weighting: during a gap, the marker's last measurement carried by the rigid motion of
  // its steadiest anchors since then is one more opinion too (and replaces the frame-to-frame
  // hold when nothing else is known).
  bool carry_from_gap_start = true;
  bool check_labels = true;
  // With weighting: each missing marker's regional PCA (region_pca_fit.h, when the subject has
  // regions) is one more weighed opinion, and the estimate when nothing nearer is known.
  bool use_regions = true;
  // With regions: each region also learns from the frames in which it is measured whole, and its
  // opinion blends that with the offline model (region_online_statistics.h).
  bool learn_regions = true;
  // Each one-ring model's estimate of each member, and eq. 2's of the marker, is tried where the
  // whole ring is measured (a few models a frame), and the variance each claims is scaled by how
  // much more it lately missed (never below its offline calibration): ring_calibration.h.
  bool calibrate_rings = true;
  // A new relabel stays on probation for this many frames: while it is, the fragment must pass
  // the taking test (eq. 3, unambiguous) every frame, else the relabel is revoked for all the
  // frames since it was taken (FrameOutput::revoked; GapEndBlender, holding those frames, gives
  // them back as estimates). The lookahead (CaptureFillOptions::lookahead) sets it; 0: none.
  int confirm_frames = 0;
};

struct FrameInput {
  std::span<const Vec3> labelled;        // one per subject marker, NaN = missing
  std::span<const Vec3> unlabelled;      // free points this frame
  std::span<const int> unlabelled_ids;   // trajectory id per free point (same fragment, same id); may be empty
};

// Id of "no free point" in FrameOutput::fragments.
inline constexpr int kNoFragment = std::numeric_limits<int>::min();

struct FrameOutput {
  std::span<Vec3> positions;          // one per subject marker
  std::span<MarkerStatus> status;     // one per subject marker
  // Optional (empty = not wanted): for a relabelled marker, the id of the free point that stands
  // for it (a source trajectory id, or -(j + 1) for the point labelled j that was rejected);
  // kNoFragment otherwise. What merging trajectories statistics are made of.
  std::span<int> fragments = {};
  // Optional (empty = not wanted): per marker, in how many frames before this one its relabel was
  // revoked (0: none). Only with GapFillerOptions::confirm_frames.
  std::span<int> revoked = {};
};

struct FillStats {
  bool ok = true;           // false: input sizes did not match the subject (output untouched)
  int measured = 0;
  int relabelled = 0;
  int filled = 0;           // PCA or rigid
  int held = 0;
  int rejected_labels = 0;  // labelled points taken as mislabelled this frame
  int changed_measured = 0;  // labelled points whose marker was output elsewhere: rejected labels
                             // that were not given back to their own marker
  int ignored_points = 0;   // non-finite or beyond capacity
};

class GapFiller : private MarkerExpectation {
 public:
  static constexpr int kMaxFreePoints = 1024;

  explicit GapFiller(const SubjectModel& model, const GapFillerOptions& options = {});

  FillStats run(const FrameInput& in, const FrameOutput& out);
  void reset();  // forget the past (new take, source reconnected)
  // How much a one-ring opinion's claimed variance is scaled up by what it lately missed
  // (calibrate_rings; 1: as calibrated offline), per entry of model.ring.
  double ring_calibration(int ring_entry) const { return ring_calibration_.ring(ring_entry); }

 private:
  void judge_suspect_labels();
  FrameEstimates frame_estimates() const;
  bool expected(int marker, Vec3& out, double* out_variance) override {
    return expected_position(marker, out, out_variance);
  }
  void estimate_rigid();
  void fit_rigid_estimate(int i);
  void relabel();
  bool solve_pca(int j);
  int pca_estimate(int i, Vec3& out, double* out_variance = nullptr, bool misfit = false);
  bool expected_position(int i, Vec3& out, double* out_variance = nullptr);
  double rigid_estimate_variance(int i, bool misfit = false) const;
  void take_free_point(int marker, int point);
  bool ambiguity_free_match(int i, int p, double distance);
  int find_free_point(int id) const;
  bool free_point_near(const Vec3& p, double reach) const;
  void refresh_estimates();
  void fill_missing();
  bool transfer_motion(int first, int last, const std::vector<int>& members, const Vec3& previous, Vec3& out);
  void add_free_point(const Vec3& p, int id);

  const SubjectModel& model_;
  GapFillerOptions options_;
  int n_ = 0;

  // Static, derived from the model.
  std::vector<int> predictor_offsets_;  // markers whose one-ring contains i (CSR)
  std::vector<int> predictor_marker_;
  std::vector<int> predictor_slot_;     // i's position in that marker's ring
  std::vector<double> eps1_, eps2_;

  // Carried from frame to frame.
  static constexpr int kRelabelRounds = 3;
  long frame_ = 0;
  long solve_stamp_ =
      0;  // this frame's: a PCA solve made in it stands until its ring changes (refresh_estimates)
  std::vector<int> assigned_id_;      // free-point trajectory currently standing for marker i
  std::vector<long> probation_start_;  // frame its relabel was taken while still on probation, else -1
  std::vector<int> refused_id_;        // a fragment whose relabel was revoked, not taken again while it lasts
  std::vector<int> revoked_;           // this frame's FrameOutput::revoked
  std::vector<Vec3> gap_offset_;      // continuity offset in the local frame, made at the gap's first frame
  MarkerTracks tracks_;               // each marker's last two frames: where it was and its own velocity
  LabelCheck label_check_;            // step 1: the labelled points held back, and their judgement
  GapStartCarry carry_;               // also where each marker's gap started

  // Per-frame scratch.
  std::vector<Vec3> current_;
  std::vector<MarkerStatus> status_;
  std::vector<char> observed_, estimated_, has_rotation_;
  std::vector<int> changed_;   // markers that became observed since the estimates were made
  std::vector<Vec3> estimate_;
  std::vector<Eigen::Matrix3d> rotation_;
  std::vector<int> available_neighbours_, missing_;
  static constexpr int kRigidSupport = 3;  // known ring members eq. 2 needs
  struct RigidQueueEntry {
    int count;
    int marker;
  };
  std::vector<RigidQueueEntry> rigid_queue_;
  std::vector<Vec3> free_points_;
  std::vector<int> free_ids_;
  std::vector<char> free_used_;
  int free_count_ = 0;
  struct Candidate {
    double distance;
    int marker;
    int point;
  };
  std::vector<Candidate> candidates_;
  std::vector<long> pca_stamp_;
  std::vector<char> pca_ok_;
  std::vector<Eigen::Matrix3d> pca_rotation_;
  PcaFit pca_fit_;
  std::vector<Vec3> pca_slot_local_;       // parallel to model.ring: reconstruction in the local frame
  std::vector<double> pca_slot_variance_;  // parallel to model.ring: calibrated predictive variance (mm^2)
  std::vector<double> pca_novelty_;        // per model: novelty_factor of this frame's solve
  std::vector<int> rigid_support_;         // observed ring members behind each rigid estimate
  std::vector<double> rigid_novelty_;      // novelty_factor of each rigid estimate's fit
  std::vector<double> rigid_variance_;     // each rigid estimate's predictive variance (mm^2, per coordinate)
  std::vector<double> rigid_member_variance_;  // per marker: its ring members' departure from rigid (mm^2)
  // Each marker's eq. 2 leverages (rigid_fit_leverage), at its ring's offset in model.ring, one
  // per member known, for the members (a bit each) they were made for: the fit's source is the
  // marker's reference ring, so they change only with which members are known.
  std::vector<double> leverage_;
  std::vector<uint32_t> leverage_mask_;
  SingleGapReconstruction single_gaps_;  // one ring member missing: the common case
  RingCalibration ring_calibration_;     // the one-ring and eq. 2 opinions' online calibration
  // Several ring members missing: per model, the observed slots (a bit each) its factor below
  // was made for, and that factor (PcaFit::factor_slots, components^2 at pattern_offset_).
  std::vector<uint32_t> pattern_mask_;
  std::vector<int> pattern_offset_;
  std::vector<double> pattern_factor_;
  bool region_estimate(int i, double other_variance, Vec3& out, double& out_variance);
  RegionPcaFit region_fit_;
  RegionOnlineStatistics region_statistics_;
  std::vector<RegionSolve> region_solves_;  // per marker's region, kept while its members seen and its shape do not change
  std::vector<Vec3> region_positions_;
  std::vector<char> region_observed_;
  std::vector<Vec3> scratch_source_, scratch_target_;
  std::vector<int> scratch_index_;
  FillStats stats_;
};

}  // namespace skinstream
