#pragma once
// Offline choice of each part's ridge on the quadratic modes of eq. 6 (PartModel::
// quadratic_ridge), by leave-one-out cross-validation over the training take.
//
// Eq. 6 fits 9 modes per coordinate to a part's members by least squares. With 9 members it
// interpolates them exactly, and with a few more it is nearly as free: the quadratic then
// follows the skin's wobble at every marker with large curvature between them. Which strength
// predicts the skin between markers best is measured on the markers themselves: the fit is a
// linear smoother of the members' deviations from the reference, d^ = d H with
// H = M Q0 (Y x Y), and for a ridge fit the miss of member i when it is left out is exactly
// r_i / (1 - H_ii), with r the fit's residual. One fit per candidate and frame.

#include <span>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"

namespace skinstream {

// The candidates: 0 (the paper's least squares) and a logarithmic grid from 1e-4 to 1e4, two
// per decade. At the top the quadratic modes are in effect gone (the linear fit alone), so the
// grid spans the paper's fit to a linear one: its top is an end of the range, not a bound
// chosen on data.
std::vector<double> quadratic_ridge_candidates();

struct QuadraticRidgeChoice {
  double ridge = 0.0;
  double loo_rms_mm = 0.0;        // leave-one-out miss at the chosen ridge, RMS over members and frames
  double loo_rms_exact_mm = 0.0;  // the same without a ridge (infinite where the fit interpolates)
  int frames = 0;
};

// One part (members' reference positions, their marker indices): the rigid fit (Horn) at up to
// `sample_frames` frames spread over the take (training: frame_count x marker_count,
// frame-major, all present), then each candidate's summed leave-one-out miss; the smallest
// wins. Parts with fewer than 9 members fit the linear modes only and get 0. With
// `segment_motions` (one per training frame: a skeleton-driven part's segment motion), that
// motion stands for the rigid fit.
QuadraticRidgeChoice choose_quadratic_ridge(const std::vector<Vec3>& reference, std::span<const int> member_markers,
                                            std::span<const Vec3> training, int frame_count, int marker_count,
                                            int sample_frames = 48, std::span<const RigidTransform> segment_motions = {});

}  // namespace skinstream
