#pragma once
// A one-ring PCA model's reconstruction of a ring member when that member alone is missing: the
// common case at runtime, and what the online checks of the ring opinions try
// (ring_calibration.h). The coefficients are then a fixed linear map of the other members (the
// normal equations depend only on which members are observed), so each map and the
// reconstruction's calibrated variance are made once, in the constructor, and a reconstruction
// is one matrix-vector product. The same fit as PcaFit (pca_fit.h), at a fraction of the cost.
//
// reconstruct() allocates nothing.

#include <span>
#include <vector>

#include "core/pca_fit.h"
#include "core/subject_model.h"

namespace skinstream {

class SingleGapReconstruction {
 public:
  explicit SingleGapReconstruction(const SubjectModel& model);

  // Model j's reconstruction of its ring member `missing_slot`, in j's local frame, from the
  // other members: `local` their positions in that frame, `slots` their ring slots (parallel).
  // Returns the observed members' squared miss against the fit (what novelty_factor reads).
  double reconstruct(int j, int missing_slot, std::span<const Vec3> local, std::span<const int> slots,
                     Vec3& out_local);
  // The calibrated predictive variance (mm^2, per coordinate) of that reconstruction, per entry of
  // model.ring (the model's ring offset plus the missing slot).
  double variance(int ring_entry) const { return variance_[ring_entry]; }

 private:
  const SubjectModel& model_;
  // Per ring entry: the coefficients' map (components x 3(d-1), row-major, at offset_) and the
  // reconstruction's calibrated variance.
  std::vector<double> map_;
  std::vector<int> offset_;
  std::vector<double> variance_;
  PcaVector deviation_, coefficients_;
};

}  // namespace skinstream
