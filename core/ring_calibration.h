#pragma once
// How much the gap filler's one-ring opinions lately deserved (beyond the paper). Each one-ring
// PCA model claims a variance for its estimate of each ring member, and eq. 2 one for its
// estimate of the marker, both calibrated on the training take. A ring that spans the two feet,
// steady while the subject stood in training, is no judge of either foot in a walk: its claim
// holds for training, not for this take. So a few models a frame, in turn, each with its marker
// and whole ring measured, estimate every member from the others (as in a one-member gap) and
// eq. 2 the marker from its ring, and the miss against the variance claimed is kept with
// forgetting (recent frames counting most: recent_miss.h). Their ratio, never below one, scales
// the claim from then on: an opinion claims no more than it has lately been shown to deserve.
//
// Everything is sized in the constructor; check() allocates nothing.

#include <array>
#include <span>
#include <vector>

#include "core/marker_status.h"
#include "core/recent_miss.h"
#include "core/single_gap_reconstruction.h"
#include "core/subject_model.h"

namespace skinstream {

class RingCalibration {
 public:
  static constexpr int kChecksPerFrame = 2;       // models checked after one frame (round robin)
  static constexpr double kMemorySeconds = 10.0;  // what was missed that long ago weighs 1/e

  RingCalibration(const SubjectModel& model, double rate_hz);

  // After each frame: the next models in turn whose marker and whole ring were measured in it
  // (`positions`, `status`: one per subject marker) are checked. `single_gaps`: the subject's.
  void check(std::span<const Vec3> positions, std::span<const MarkerStatus> status,
             SingleGapReconstruction& single_gaps);
  // The factor (>= 1; 1: as calibrated offline) on the variance claimed by a one-ring model's
  // estimate of a member, per entry of model.ring ...
  double ring(int ring_entry) const { return ring_calibration_[ring_entry]; }
  // ... and by eq. 2's estimate of marker i from its ring.
  double rigid(int i) const { return rigid_calibration_[i]; }
  void reset();  // back to the offline calibration

 private:
  const SubjectModel& model_;
  double rate_hz_ = 120.0;
  long frame_ = 0;
  int cursor_ = 0;
  long nominal_frames_ = 1;              // between a model's checks when every ring is seen
  std::vector<RecentMiss> ring_recent_;  // parallel to model.ring
  std::vector<double> ring_calibration_;
  std::vector<long> checked_frame_;       // per model: the frame it was last checked
  std::vector<RecentMiss> rigid_recent_;  // per marker
  std::vector<double> rigid_calibration_;
  std::array<Vec3, SubjectModel::kMaxRing> source_, target_;
  std::array<int, SubjectModel::kMaxRing> slots_;
};

}  // namespace skinstream
