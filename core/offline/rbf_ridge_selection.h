#pragma once
// Offline choice of each part's ridge for eq. 7 (a smoothing term added to the kernel
// diagonal), by leave-one-out cross-validation over the training take.
//
// The cubic B-spline is not positive definite as a radial function in 3D, and with a part's
// ~150 members at the paper's dilation the exact interpolant of eq. 7 is often near-singular:
// it passes through every member but swings between them. Which smoothing predicts the skin
// between markers best is measured on the markers themselves: leave one member out, fit the
// rest, see how far the fit misses it. Rippa's formula (1999) gives every member's
// leave-one-out miss from one solve: e_i = c_i / (A^-1)_ii with A = Phi + lambda I and
// c = A^-1 r. With Phi = V diag(mu) V^T once per frame, every lambda costs O(Y^2).

#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/part_model.h"

namespace skinstream {

// The candidates: 0 (exact interpolation, the paper as written) and a logarithmic grid from
// 1e-5 to 1, four per decade, in kernel units (phi(0) = 2/3). The top is not a neutral bound:
// small parts pick it, and with a grid up to 100 they pick 100 (no residual in effect) and the
// synthetic takes all got worse. Leaving a marker out of a small part opens a gap wider than
// any vertex sees, so leave-one-out over-smooths there (README, skin deformation).
std::vector<double> rbf_ridge_candidates();

// Sum over members of |e_i|^2 (mm^2), Rippa's formula, for each ridge; one frame's centres
// (p~ = A_t q^0, local frame, 3 x Y) and residuals (Y x 3). A candidate whose matrix is
// singular scores +infinity.
std::vector<double> leave_one_out_squared_errors(const Eigen::Matrix3Xd& centres, const Eigen::MatrixX3d& residuals,
                                                 double dilation, std::span<const double> ridges);

struct RidgeChoice {
  double ridge = 0.0;
  double loo_rms_mm = 0.0;        // leave-one-out miss at the chosen ridge, RMS over members and frames
  double loo_rms_exact_mm = 0.0;  // the same without a ridge (exact interpolation)
  int frames = 0;
};

// One part: fits rigid + quadratic (eq. 6) to its members at up to `sample_frames` frames spread
// over the take (training: frame_count x marker_count, frame-major, all present) and picks the
// candidate with the smallest summed leave-one-out error. A part without an RBF term (dilation
// 0) gets ridge 0. With `segment_motions` (one per training frame: a skeleton-driven part's
// segment motion), that motion stands for the rigid fit.
RidgeChoice choose_rbf_ridge(const PartModel& part, std::span<const int> member_markers, std::span<const Vec3> training,
                             int frame_count, int marker_count, int sample_frames = 48,
                             std::span<const RigidTransform> segment_motions = {});

}  // namespace skinstream
