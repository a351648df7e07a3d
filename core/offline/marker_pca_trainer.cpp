#include "core/offline/marker_pca_trainer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "core/absolute_orientation.h"
#include "core/pca_fit.h"

namespace skinstream {

namespace {

// Leave one ring member out at a time on (a subsample of) the training frames, as the runtime
// will see it, and compare the model's claimed predictive variance with the error it makes;
// also measure the error of the marker's own rigid estimate (eq. 2).
void calibrate(const Capture& capture, int marker, const std::vector<int>& ring,
               const std::vector<Vec3>& ring_local_reference, const std::vector<int>& usable,
               const PcaTrainingOptions& options, MarkerPcaModel& model) {
  const int d = static_cast<int>(ring.size());
  const double floor = options.noise_floor_mm * options.noise_floor_mm;
  model.slot_calibration = Eigen::VectorXd::Ones(d);
  model.rigid_variance = floor;
  const int step = std::max<int>(1, static_cast<int>(usable.size()) / std::max(1, options.calibration_frames));
  std::vector<Vec3> relative(d), source, target;
  std::vector<int> slots;
  Eigen::VectorXd squared_error = Eigen::VectorXd::Zero(d), claimed = Eigen::VectorXd::Zero(d);
  double rigid_error = 0.0;
  int frames = 0;
  PcaFit fit;
  for (size_t u = 0; u < usable.size(); u += step) {
    const int f = usable[u];
    const Vec3 origin = capture.at(f, marker);
    for (int j = 0; j < d; ++j) relative[j] = capture.at(f, ring[j]) - origin;
    RigidTransform rigid;
    std::vector<Vec3> world(d);
    for (int j = 0; j < d; ++j) world[j] = capture.at(f, ring[j]);
    fit_rigid(ring_local_reference, world, rigid);
    rigid_error += (rigid.translation - origin).squaredNorm() / 3.0;
    for (int left_out = 0; left_out < d && d >= 3; ++left_out) {
      source.clear();
      target.clear();
      slots.clear();
      for (int j = 0; j < d; ++j)
        if (j != left_out) {
          source.push_back(relative[j]);
          target.push_back(ring_local_reference[j]);
          slots.push_back(j);
        }
      Eigen::Matrix3d rotation;
      fit_rotation(source, target, rotation);  // eq. 5 from what is observed
      for (Vec3& p : source) p = rotation * p;
      if (!fit.fit(model, slots, source)) continue;
      squared_error(left_out) += (fit.reconstruct(model, left_out) - rotation * relative[left_out]).squaredNorm() / 3.0;
      claimed(left_out) += fit.predictive_variance(model, left_out);
    }
    ++frames;
  }
  if (frames == 0) return;
  model.rigid_variance = std::max(floor, rigid_error / frames);
  for (int j = 0; j < d; ++j)
    if (claimed(j) > 0) model.slot_calibration(j) = std::max(1.0, squared_error(j) / claimed(j));
}

}  // namespace

void keep_principal_components(const Eigen::MatrixXd& covariance, double variance_kept, double floor, MarkerPcaModel& model) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(covariance);
  const Eigen::VectorXd values = eig.eigenvalues().reverse().cwiseMax(0.0);
  const int dims = static_cast<int>(covariance.rows());
  const double total = values.sum();
  // Components below a micrometre of spread are round-off, not deformation.
  constexpr double kNumericalZero = 1e-6;  // mm^2
  int kept = 0;
  double explained = 0.0;
  while (kept < dims && values(kept) > kNumericalZero && explained < variance_kept * total) {
    explained += values(kept);
    ++kept;
  }
  model.basis = eig.eigenvectors().rowwise().reverse().leftCols(kept);
  model.variance = values.head(kept).cwiseMax(floor);
  model.residual_variance = std::max(floor, kept < dims ? (total - explained) / (dims - kept) : 0.0);
}

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
    model.slot_calibration = Eigen::VectorXd::Ones(d);
    model.rigid_variance = floor;
    return model;
  }
  samples.conservativeResize(Eigen::NoChange, columns);
  model.mean = samples.rowwise().mean();
  samples.colwise() -= model.mean;
  keep_principal_components(samples * samples.transpose() / static_cast<double>(columns), options.variance_kept, floor, model);
  calibrate(capture, marker, ring, ring_local_reference, usable, options, model);
  return model;
}

}  // namespace skinstream
