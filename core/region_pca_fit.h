#pragma once
// A marker's regional PCA opinion (beyond the paper): the marker and the markers that stay
// nearest to it over the training take (its region, subject_model.h), modelled together by a PCA
// of their shape after rigid alignment to the mean shape. Unlike the one-ring models, whose frame
// is built on the marker or on one neighbour, the region is aligned on whichever of its members
// are seen, so it still speaks when the marker's own neighbourhood is mostly gone (three of a
// foot's four markers occluded: the shin, the knee and the other foot still say how the foot
// moves in the gait).
//   1. Align the observed members with the mean shape (Horn): the region's frame.
//   2. Condition the shape's Gaussian (region_shape_gaussian.h) on them: for a PCA model this is
//      the same estimate as a least-squares fit of the coefficients with the PCA prior
//      (pca_fit.h), and it holds just as well for a covariance learned online, of any rank.
//   3. Align again on every member, the missing ones as just estimated (training aligned
//      complete shapes), and condition again; repeat until the estimate settles (at most 10
//      rounds: on a walk's two legs, where the legs' opposite swing looks like a turn of the
//      whole, one round left 34 mm of error on a synthetic foot and ten 5 mm).
// The estimate is member 0's conditional mean carried back to the world; its variance per
// coordinate the conditional variance times the calibration. What depends only on the shape and
// on which members are seen (region_solve.h) a caller may keep across frames. Allocation-free.

#include <array>
#include <span>

#include "core/absolute_orientation.h"
#include "core/pca_fit.h"
#include "core/region_shape_gaussian.h"
#include "core/region_solve.h"
#include "core/subject_model.h"

namespace skinstream {

class RegionPcaFit {
 public:
  // `positions` and `observed` are parallel to the region's members (slot 0: the marker to
  // estimate, whose own position is not used). False when fewer than three other members are
  // observed or the observed members' covariance cannot be factored.
  bool estimate(const RegionShapeGaussian& shape, std::span<const Vec3> positions, std::span<const char> observed,
                Vec3& out, double& out_variance);
  // The same from a solve prepared for the members observed now (region_solve.h), kept by the
  // caller while they and the shape stay the same; `positions` parallel to the members.
  void estimate(const RegionSolve& solve, std::span<const Vec3> positions, Vec3& out, double& out_variance);
  // The same from the offline model (false too when it was never trained).
  bool estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                Vec3& out, double& out_variance);

 private:
  void align_and_condition(const RegionSolve& solve, int aligned);

  static constexpr int kMaxAlignments = 10;
  static constexpr double kConverged = 0.5;  // mm
  RigidTransform to_region_;  // world -> the region's frame
  std::array<Vec3, SubjectModel::kMaxRing> world_, mean_;
  std::array<Vec3, SubjectModel::kMaxRing> hidden_;  // the hidden members' conditional means, region's frame
  PcaVector deviation_;  // observed members in the region's frame less their mean

  RegionSolve own_solve_;
  RegionShapeGaussian from_model_;
};

}  // namespace skinstream
