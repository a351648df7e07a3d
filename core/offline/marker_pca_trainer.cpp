#include "core/offline/marker_pca_trainer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "core/absolute_orientation.h"

namespace skinstream {

MarkerPcaModel train_marker_pca(const Capture& capture, int marker, const std::vector<int>& ring,
                                const std::vector<Vec3>& ring_local_reference, const PcaTrainingOptions& options) {
  const int d = static_cast<int>(ring.size());
  const int dims = 3 * d;
  std::vector<int> usable;
  for (int f = 0; f < capture.frame_count; ++f) {
    bool all = capture.present(f, marker);
    for (int j = 0; j < d && all; ++j) all = capture.present(f, ring[j]);
    if (all) usable.push_back(f);
  }
  const int step = std::max<int>(1, static_cast<int>(usable.size()) / std::max(1, options.max_frames));

  Eigen::MatrixXd samples(dims, (usable.size() + step - 1) / step);
  std::vector<Vec3> relative(d);
  Eigen::Matrix3d rotation;
  int columns = 0;
  for (size_t u = 0; u < usable.size(); u += step) {
    const int f = usable[u];
    const Vec3 origin = capture.at(f, marker);
    for (int j = 0; j < d; ++j) relative[j] = capture.at(f, ring[j]) - origin;
    fit_rotation(relative, ring_local_reference, rotation);  // eq. 5
    for (int j = 0; j < d; ++j) samples.block<3, 1>(3 * j, columns) = rotation * relative[j];
    ++columns;
  }

  MarkerPcaModel model;
  model.training_frames = columns;
  const double floor = options.noise_floor_mm * options.noise_floor_mm;
  if (columns == 0 || dims == 0) {
    // Never seen complete: the reference shape is the whole model.
    model.mean.resize(dims);
    for (int j = 0; j < d; ++j) model.mean.segment<3>(3 * j) = ring_local_reference[j];
    model.basis.resize(dims, 0);
    model.variance.resize(0);
    model.residual_variance = floor;
    return model;
  }
  samples.conservativeResize(Eigen::NoChange, columns);
  model.mean = samples.rowwise().mean();
  samples.colwise() -= model.mean;
  const Eigen::MatrixXd covariance = samples * samples.transpose() / static_cast<double>(columns);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(covariance);
  const Eigen::VectorXd values = eig.eigenvalues().reverse().cwiseMax(0.0);
  const double total = values.sum();
  // Components below a micrometre of spread are round-off, not deformation.
  constexpr double kNumericalZero = 1e-6;  // mm^2
  int kept = 0;
  double explained = 0.0;
  while (kept < dims && values(kept) > kNumericalZero && explained < options.variance_kept * total) {
    explained += values(kept);
    ++kept;
  }
  model.basis = eig.eigenvectors().rowwise().reverse().leftCols(kept);
  model.variance = values.head(kept).cwiseMax(floor);
  model.residual_variance = std::max(floor, kept < dims ? (total - explained) / (dims - kept) : 0.0);
  return model;
}

}  // namespace skinstream
