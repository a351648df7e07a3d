#pragma once
// The regions and regional PCA models of region_pca_fit.h, built offline from the training take.
//
// A marker's region is chosen from evidence in the training take, not from the reference pose:
// the marker, then the markers nearest to it by skin distance (the mean plus two standard
// deviations of the pair's distance, marker_distance_stats.h), so markers that stay rigid with it
// come first and a marker that only passes by (the other foot in a walk, a hand at the hip) comes
// after every steady one of similar distance.
//
// Its model: generalised Procrustes alignment of the region over the training frames where all
// of it is present, then PCA keeping `variance_kept`. The predictive variance of member 0 is
// calibrated on training frames the model did not see (a model of the first three quarters of
// those frames, tried on the last quarter), with the marker and its two nearest members left out
// together: a neighbourhood gone, which is when this opinion matters.

#include <Eigen/Core>
#include <vector>

#include "core/capture.h"
#include "core/subject_model.h"

namespace skinstream {

struct RegionPcaOptions {
  int size = SubjectModel::kMaxRing;  // members, the marker included
  double variance_kept = 0.99;
  int max_frames = 3000;            // evenly spaced subsample of the usable frames
  int min_frames = 40;              // fewer usable frames: an untrained model (no opinion)
  double noise_floor_mm = 0.5;      // residual variance never below this squared
  double calibration_share = 0.25;  // the last quarter of the usable frames calibrates
  int calibration_frames = 200;
};

// Marker i's region: i first, then up to size - 1 others ascending by `skin_distance` (N x N;
// pairs never seen together, at +infinity, are left out).
std::vector<int> marker_region(const Eigen::MatrixXd& skin_distance, int i, int size);

// `members` are channel indices of `capture`, the marker to estimate first.
MarkerPcaModel train_region_pca(const Capture& capture, const std::vector<int>& members, const RegionPcaOptions& options = {});

}  // namespace skinstream
