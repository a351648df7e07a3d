#pragma once
// Fitting a marker's neighbourhood PCA model to the part of its one-ring that is observed
// (section 4.3), shared by the runtime filler and the offline calibration so both do the same.
//
// The coefficients c minimise |B_O c - (z_O - mean_O)|^2 / residual_variance + sum c_k^2 / variance_k:
// least squares on the observed rows with the PCA variances as a Gaussian prior, so a ring seen
// only in part cannot push the coefficients beyond what training saw. Allocation-free.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <span>

#include "core/subject_model.h"

namespace skinstream {

constexpr int kMaxRingDims = 3 * SubjectModel::kMaxRing;
using PcaMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRingDims, kMaxRingDims>;
using PcaVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRingDims, 1>;

// A squared miss over the squared miss expected of it, at least 1: how much a claim's variance
// grows when what it was fitted to fits worse than it should.
inline double misfit_ratio(double squared_miss, double expected) {
  return expected > 0.0 && squared_miss > expected ? squared_miss / expected : 1.0;
}

// How much less a model's claim is worth on a pose unlike those it was trained on: the observed
// members' squared miss against the model's own estimate of them, over what its residual leads
// one to expect (three coordinates a member); at least 1.
inline double novelty_factor(double squared_miss, int observed, double residual_variance) {
  return misfit_ratio(squared_miss, 3.0 * observed * residual_variance);
}

class PcaFit {
 public:
  // `slots`: indices of the observed ring members; `local`: their positions in the marker's
  // local frame (eq. 4). Returns false when the system cannot be solved.
  bool fit(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local);

  // The same fit in two steps, for a caller that sees one set of observed slots frame after
  // frame: the normal matrix depends only on which slots are observed, so its lower Cholesky
  // factor (k x k, column-major, k = components) is made once per set (false when it cannot
  // be) and each fit is then a right-hand side and two triangular solves.
  static bool factor_slots(const MarkerPcaModel& model, std::span<const int> slots, std::span<double> out_factor);
  void fit_factored(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local,
                    std::span<const double> factor);

  // The model's reconstruction of ring member `slot` in the local frame, and its predictive
  // variance per coordinate (mm^2): coefficient uncertainty seen through that member's rows,
  // plus the residual.
  Vec3 reconstruct(const MarkerPcaModel& model, int slot) const;
  double predictive_variance(const MarkerPcaModel& model, int slot) const;

  const PcaVector& coefficients() const { return coefficients_; }
  // Sum over the observed members of |local - reconstruction|^2 (mm^2): what novelty_factor reads.
  double squared_miss(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local) const;

 private:
  PcaVector coefficients_;
  Eigen::LLT<PcaMatrix> llt_;
};

}  // namespace skinstream
