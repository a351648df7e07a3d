#pragma once
// Reference gap filler: the offline PCA method of Gløersen & Federolf 2016, "Predicting Missing
// Marker Trajectories in Human Motion Data Using Marker Intercorrelations", PLoS ONE 11(3)
// e0152616, which builds on Federolf 2013 (PLoS ONE 8(10) e78689). Written from the published
// description and the documented behaviour of the authors' MATLAB function PredictMissingMarkers
// (its default strategy "R2" and default parameters). No code was copied.
//
// Markers are the labelled channels that are present at least once. Unlabelled channels are
// returned unchanged, and a channel that is never present stays missing. For each marker i with
// gaps ("the target"):
//  1. Data: frames x 3M, row f = (x1 y1 z1 x2 ... zM), mm.
//  2. Moving frame, as published: subtract from every marker, per frame, the mean position of the
//     markers that have no gap. EXTENSION: the published code has no answer when every marker has
//     a gap (it would take the mean of an empty set), which is what plan_gaps produces. In that
//     case each model uses the mean of its own non-target markers, which are present in every
//     row it touches, so the frame is the same function of the data in training and filling. A
//     model with no other marker uses the centroid of an additive fit p_j(f) ~ c(f) + o_j over
//     the present samples (5 alternating least-squares rounds). That fit compensates each absent
//     marker's mean offset, so the centroid does not jump when markers drop out. Frames in which
//     no marker is present stay missing.
//  3. Distances: d(i, j) = mean |p_i - p_j| over the frames where both are present.
//  4. Strategy R2 (handling several missing markers). A model keeps the target, every gap-free
//     marker and each marker j with gaps unless (a) j is distal, i.e.
//     d(i, j) > distal_threshold * mean_j d(i, j) (the mean includes d(i, i) = 0, as published),
//     or (b) j is missing in a frame the model must fill. It is trained on every frame where all
//     the kept markers are present. DEVIATION (default grouping = per_gap): rule (b) is applied
//     to each gap of the target separately, not to the union of its gaps, so a neighbour that is
//     missing during one gap still helps with the others. Gaps that select the same markers
//     share one model. grouping = per_marker reproduces the published grouping: one model per
//     target, built from all of its gaps at once. Both groupings are identical when the target
//     has a single gap.
//  5. Normalisation: give each column zero mean and unit population standard deviation over the
//     training frames (a constant column keeps scale 1). Then multiply marker j's columns by
//     w_j = exp(-d(i, j)^2 / (2 sigma^2)), with sigma = weight_scale_mm, and the target's by
//     w_i = missing_marker_weight. The target then barely shapes the principal components but can
//     still be read off them.
//  6. PCA: eigenvectors of the covariance (the SVD of the normalised matrix / sqrt(n - 1)) of the
//     training matrix N, giving V, and of N0 = N with the target's columns zeroed, giving V0. Both
//     keep k = max(k_N, k_N0) components. k_X is the smallest number of leading components whose
//     singular values reach min_cumulative_singular_values of the sum. As published, the 99 %
//     applies to singular values, not to variance.
//  7. Reconstruction (Federolf 2013), as published. For each frame to fill, m0 is its normalised,
//     weighted row with the target's columns zero; its scores in the incomplete basis s0 = m0 V0
//     go through the transformation T = V'V0 into the complete basis: r = s0 T V'. The target's
//     coordinates are mean + r * std / w_i, plus the moving frame. (For row scores the exact
//     change of basis would be T' = V0'V. The two agree while V0 equals V up to column signs,
//     which the small w_i ensures. They differed by under 4 % in mean error on CMU 85_12 and
//     negligibly on the tests' synthetic data, so the published form is kept.)
//
// Tuning note: the published distal_threshold (0.5) suits captures where most markers have no
// gap. When every marker has gaps, it keeps only markers well inside the average distance. On
// CMU 85_12 with plan_gaps defaults, 0.75 gave about 40 % lower mean error (three seeds). The
// default stays published.
//
// Accuracy: a marker that is an exact affine combination of the others (or a marker on a rigid
// body with the others) is recovered with a bias that shrinks as w_i^2 (about 0.01 mm on a
// 10 cm cluster with the default w_i = 0.02), provided the 99 % cut keeps every direction that
// matters.
//
// Cost: one covariance (training frames x (3 x kept markers)^2) and two symmetric
// eigendecompositions per model. On CMU 85_12 (41 markers, 4499 frames, 7 % of samples removed
// by plan_gaps defaults) this takes about 0.1 s (0.06-0.15 s measured on a busy 2-core machine).
//
// Not in the paper: a model with fewer than min_training_frames training frames leaves its gaps
// missing. The published code would fail or return NaN.

#include "core/capture.h"

namespace skinstream {

enum class GloersenGrouping {
  per_gap,     // rule (b) per gap of the target (default, see above)
  per_marker,  // rule (b) over all gaps of the target at once, as the published code does
};

struct GloersenOptions {
  // The first four are the published defaults.
  double weight_scale_mm = 200.0;                // sigma of the distance weights
  double missing_marker_weight = 0.02;           // w_i of the target
  double distal_threshold = 0.5;                 // R2 distal cut, relative to the mean distance
  double min_cumulative_singular_values = 0.99;  // share of the singular values the kept PCs reach
  int min_training_frames = 2;                   // a model with fewer leaves its gaps missing
  GloersenGrouping grouping = GloersenGrouping::per_gap;
};

// Throws std::invalid_argument for a non-positive weight scale, missing-marker weight or distal
// threshold, a singular-value share outside (0, 1) (at 1 the projection is the identity and the
// target stays at its mean), min_training_frames < 2, or positions that do not match
// labels x frame_count.
Capture fill_gloersen_pca(const Capture& capture, const GloersenOptions& options = {});

}  // namespace skinstream
