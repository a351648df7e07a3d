#include "core/offline/region_pca_trainer.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/absolute_orientation.h"
#include "core/offline/marker_pca_trainer.h"
#include "core/region_pca_fit.h"

namespace skinstream {
namespace {

std::vector<Vec3> shape_at(const Capture& capture, const std::vector<int>& members, int f) {
  std::vector<Vec3> shape;
  for (int m : members) shape.push_back(capture.at(f, m));
  return shape;
}

// Generalised Procrustes alignment of the region over `frames`, then PCA; calibration 1.
MarkerPcaModel fit_model(const Capture& capture, const std::vector<int>& members, std::span<const int> frames,
                         const RegionPcaOptions& options) {
  const int size = static_cast<int>(members.size()), dims = 3 * size;
  const int step = std::max<int>(1, static_cast<int>(frames.size()) / std::max(1, options.max_frames));
  std::vector<std::vector<Vec3>> shapes;
  for (size_t u = 0; u < frames.size(); u += step) shapes.push_back(shape_at(capture, members, frames[u]));
  const int count = static_cast<int>(shapes.size());
  std::vector<Vec3> mean = shapes.front();
  Eigen::MatrixXd samples(dims, count);
  for (int round = 0; round < 4; ++round) {
    Vec3 centroid = Vec3::Zero();
    for (const Vec3& p : mean) centroid += p / size;
    for (Vec3& p : mean) p -= centroid;
    for (int s = 0; s < count; ++s) {
      RigidTransform t;
      fit_rigid(shapes[s], mean, t);
      for (int k = 0; k < size; ++k) samples.block<3, 1>(3 * k, s) = t.apply(shapes[s][k]);
    }
    const Eigen::VectorXd average = samples.rowwise().mean();
    for (int k = 0; k < size; ++k) mean[k] = average.segment<3>(3 * k);
  }
  MarkerPcaModel model;
  model.training_frames = count;
  model.mean = samples.rowwise().mean();
  samples.colwise() -= model.mean;
  const double floor = options.noise_floor_mm * options.noise_floor_mm;
  keep_principal_components(samples * samples.transpose() / static_cast<double>(count), options.variance_kept, floor, model);
  model.slot_calibration = Eigen::VectorXd::Ones(size);
  model.rigid_variance = floor;  // not used by a region
  return model;
}

// Member 0 estimated with members 0-2 left out, on `frames`: mean squared error over the
// variance claimed (at least 1).
double calibration(const MarkerPcaModel& model, const Capture& capture, const std::vector<int>& members,
                   std::span<const int> frames, int samples) {
  const int size = static_cast<int>(members.size());
  std::vector<char> observed(size, 1);
  for (int k = 0; k < std::min(3, size); ++k) observed[k] = 0;
  RegionPcaFit fit;
  RegionShapeGaussian shape;  // made once: every frame asks the same model
  region_gaussian_from_pca(model, shape);
  double squared_error = 0.0, claimed = 0.0;
  const int step = std::max<int>(1, static_cast<int>(frames.size()) / std::max(1, samples));
  for (size_t u = 0; u < frames.size(); u += step) {
    const std::vector<Vec3> truth = shape_at(capture, members, frames[u]);
    Vec3 estimate;
    double variance = 0.0;
    if (!fit.estimate(shape, truth, observed, estimate, variance)) continue;
    squared_error += (estimate - truth[0]).squaredNorm() / 3.0;
    claimed += variance;
  }
  return claimed > 0 ? std::max(1.0, squared_error / claimed) : 1.0;
}

}  // namespace

std::vector<int> marker_region(const Eigen::MatrixXd& skin_distance, int i, int size) {
  std::vector<int> others;
  for (int j = 0; j < skin_distance.rows(); ++j)
    if (j != i && std::isfinite(skin_distance(i, j))) others.push_back(j);
  const int k = std::min<int>(size - 1, static_cast<int>(others.size()));
  std::partial_sort(others.begin(), others.begin() + k, others.end(),
                    [&](int a, int b) { return skin_distance(i, a) < skin_distance(i, b); });
  std::vector<int> region = {i};
  region.insert(region.end(), others.begin(), others.begin() + k);
  return region;
}

MarkerPcaModel train_region_pca(const Capture& capture, const std::vector<int>& members, const RegionPcaOptions& options) {
  std::vector<int> usable;
  for (int f = 0; f < capture.frame_count; ++f) {
    bool all = true;
    for (int m : members) all = all && capture.present(f, m);
    if (all) usable.push_back(f);
  }
  const int size = static_cast<int>(members.size());
  if (static_cast<int>(usable.size()) < options.min_frames || size < 4) {
    MarkerPcaModel untrained;  // training_frames 0: never used
    untrained.mean = Eigen::VectorXd::Zero(3 * size);
    untrained.basis.resize(3 * size, 0);
    untrained.residual_variance = options.noise_floor_mm * options.noise_floor_mm;
    untrained.slot_calibration = Eigen::VectorXd::Ones(size);
    untrained.rigid_variance = untrained.residual_variance;
    return untrained;
  }
  const std::span<const int> all(usable);
  const size_t cut = static_cast<size_t>((1.0 - options.calibration_share) * usable.size());
  const MarkerPcaModel first_part = fit_model(capture, members, all.first(cut), options);
  MarkerPcaModel model = fit_model(capture, members, all, options);
  model.slot_calibration(0) = calibration(first_part, capture, members, all.subspan(cut), options.calibration_frames);
  return model;
}

}  // namespace skinstream
