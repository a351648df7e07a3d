#pragma once
// The part of a region's estimate (region_pca_fit.h) that depends only on its shape and on which
// members are observed, solved once and kept while neither changes: a marker's gap lasts hundreds
// of frames, its region's observed members change rarely in it, and a region in a gap does not
// learn. With the observed members O and the hidden ones H (member 0 always among them) and the
// shape's covariance C (residual r added on O):
//   gain      = (C_OO + r I)^-1 C_OH, so E[H | O] = mean_H + gain^T (aligned O - mean_O): what
//               every round of the alternating alignment needs, a small product instead of two
//               triangular solves;
//   lower     = L with L L^T = C_OO + r I, for the observed members' miss (novelty) once a frame;
//   variance  = member 0's conditional variance per coordinate (residual included), before its
//               calibration and novelty.
// Fixed capacity (kMaxRing members): preparing and using it allocate nothing.

#include <array>
#include <cstdint>
#include <span>

#include "core/pca_fit.h"
#include "core/region_shape_gaussian.h"
#include "core/subject_model.h"

namespace skinstream {

struct RegionSolve {
  uint32_t observed_mask = 0;  // bit k: member k observed; 0: nothing kept
  long shape_version = -1;
  int observed = 0;  // members in observed_slots
  int hidden = 0;    // members in hidden_slots: member 0 first, then the unobserved in order
  std::array<int, SubjectModel::kMaxRing> observed_slots{}, hidden_slots{};
  PcaVector mean;        // the shape's mean, 3 * members
  PcaMatrix lower;       // 3 observed square
  PcaMatrix gain;        // 3 observed x 3 hidden
  double variance = 0.0;
  double calibration = 1.0;
  double residual_variance = 0.0;

  // Whether this holds a solve for these members seen and this shape (never after a failed prepare).
  bool matches(uint32_t mask, long version) const {
    return observed_mask != 0 && observed_mask == mask && shape_version == version;
  }
};

// Which of members 1.. are observed, as a RegionSolve's mask (member 0's own flag is not read).
uint32_t region_observed_mask(std::span<const char> observed);

// Solves for `shape` with the members in `mask` observed, kept under `shape_version`. False (and
// nothing kept) when fewer than three are observed or their covariance cannot be factored.
bool prepare_region_solve(const RegionShapeGaussian& shape, uint32_t mask, long shape_version, RegionSolve& out);

}  // namespace skinstream
