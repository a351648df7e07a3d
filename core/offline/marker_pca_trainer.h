#pragma once
// Trains the PCA model of one marker's neighbourhood (section 4.3): over the training frames in
// which the marker and all of its one-ring are present, the one-ring is brought into the local
// frame by the rotation of eq. 5 and the resulting 3 * ring_size vectors are decomposed,
// keeping the fewest components that explain `variance_kept` of the variance.

#include <vector>

#include "core/capture.h"
#include "core/subject_model.h"

namespace skinstream {

struct PcaTrainingOptions {
  double variance_kept = 0.99;
  int max_frames = 6000;              // evenly spaced subsample of the usable frames
  double noise_floor_mm = 0.5;        // residual variance never below this squared
  int calibration_frames = 300;       // frames used to calibrate the predictive variances
};

// From the covariance of centred samples (mm^2): the fewest leading components that explain
// `variance_kept` (round-off ones never), their variances and the residual per dimension, none
// below `floor` (mm^2), into `model`'s basis, variance and residual_variance.
void keep_principal_components(const Eigen::MatrixXd& covariance, double variance_kept, double floor, MarkerPcaModel& model);

// `marker` and `ring` are channel indices of `capture`; `ring_local_reference` the eq. 1 positions.
MarkerPcaModel train_marker_pca(const Capture& capture, int marker, const std::vector<int>& ring,
                                const std::vector<Vec3>& ring_local_reference, const PcaTrainingOptions& options);

}  // namespace skinstream
