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
// coordinate the conditional variance times the calibration. Allocation-free.

#include <array>
#include <cstdint>
#include <span>

#include "core/absolute_orientation.h"
#include "core/pca_fit.h"
#include "core/region_shape_gaussian.h"
#include "core/subject_model.h"

namespace skinstream {

// The Cholesky factor of a region's observed members' covariance, kept by a caller from frame
// to frame: it depends only on which members are observed and on the shape, and while neither
// changes (a region in a gap does not learn) it is reused.
struct RegionFactor {
  uint32_t observed_mask = 0;  // 0: nothing kept
  long shape_version = -1;
  PcaMatrix lower;
};

class RegionPcaFit {
 public:
  // `positions` and `observed` are parallel to the region's members (slot 0: the marker to
  // estimate, whose own position is not used). False when fewer than three other members are
  // observed or the observed members' covariance cannot be factored.
  // With `kept`, the factor is taken from it when made for these members and `shape_version`,
  // else made there.
  bool estimate(const RegionShapeGaussian& shape, std::span<const Vec3> positions, std::span<const char> observed,
                Vec3& out, double& out_variance, RegionFactor* kept = nullptr, long shape_version = 0);
  // The same from the offline model (false too when it was never trained).
  bool estimate(const MarkerPcaModel& model, std::span<const Vec3> positions, std::span<const char> observed,
                Vec3& out, double& out_variance);

 private:
  void align_and_condition(const RegionShapeGaussian& shape, int aligned);
  Vec3 conditional_mean(const RegionShapeGaussian& shape, int slot) const;

  static constexpr int kMaxAlignments = 10;
  static constexpr double kConverged = 0.5;  // mm
  int observed_count_ = 0;
  RigidTransform to_region_;  // world -> the region's frame
  std::array<Vec3, SubjectModel::kMaxRing> world_, mean_;
  std::array<int, SubjectModel::kMaxRing> slots_;
  bool factor(const RegionShapeGaussian& shape, uint32_t mask, RegionFactor& out);

  RegionFactor own_factor_;
  const PcaMatrix* lower_ = nullptr;  // L of the observed members' covariance (residual included) = L L^T
  PcaVector weights_;  // (L L^T)^-1 (observed in the region's frame - their mean)
  PcaMatrix cross_;    // scratch: covariance of member 0 with the observed members
  RegionShapeGaussian from_model_;
};

}  // namespace skinstream
