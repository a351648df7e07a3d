#pragma once
// A marker's regional PCA opinion (beyond the paper): the marker and the markers that stay
// nearest to it over the training take (its region, subject_model.h), modelled together by a PCA
// of their shape after rigid alignment to the mean shape. Unlike the one-ring models, whose frame
// is built on the marker or on one neighbour, the region is aligned on whichever of its members
// are seen, so it still speaks when the marker's own neighbourhood is mostly gone (three of a
// foot's four markers occluded: the shin, the knee and the other foot still say how the foot
// moves in the gait).
//   1. Align the observed members with the mean shape (Horn): the region's frame.
//   2. Fit the coefficients to them (pca_fit.h: least squares with the PCA prior).
//   3. Align again on every member, the missing ones as just reconstructed (training aligned
//      complete shapes), and fit again; repeat until the estimate settles (at most 10 rounds:
//      on a walk's two legs, where the legs' opposite swing looks like a turn of the whole, one
//      round left 34 mm of error on a synthetic foot and ten 5 mm).
// The estimate is member 0's reconstruction carried back to the world; its variance per
// coordinate the fit's predictive variance times the calibration of slot 0. Allocation-free.

#include <array>
#include <span>

#include "core/absolute_orientation.h"
#include "core/pca_fit.h"
#include "core/subject_model.h"

namespace skinstream {

class RegionPcaFit {
 public:
  // `positions` and `observed` are parallel to the model's members (slot 0: the marker to
  // estimate, whose own position is not used). False when fewer than three other members are
  // observed, the model was never trained, or the fit fails.
  bool estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                Vec3& out, double& out_variance);

 private:
  bool align_and_fit(const MarkerPcaModel& model, int aligned, int fitted);

  static constexpr int kMaxAlignments = 10;
  static constexpr double kConverged = 0.5;  // mm
  PcaFit fit_;
  RigidTransform to_region_;  // world -> the region's frame
  std::array<Vec3, SubjectModel::kMaxRing> world_, mean_, local_;
  std::array<int, SubjectModel::kMaxRing> slots_;
};

}  // namespace skinstream
