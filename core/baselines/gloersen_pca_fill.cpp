#include "core/baselines/gloersen_pca_fill.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

namespace skinstream {

namespace {

void validate(const Capture& capture, const GloersenOptions& options) {
  if (capture.frame_count < 0 ||
      capture.positions.size() != static_cast<size_t>(capture.frame_count) * capture.labels.size())
    throw std::invalid_argument("fill_gloersen_pca: positions do not match labels x frame_count");
  if (!(options.weight_scale_mm > 0.0) || !std::isfinite(options.weight_scale_mm))
    throw std::invalid_argument("fill_gloersen_pca: weight_scale_mm must be positive");
  if (!(options.missing_marker_weight > 0.0) || !std::isfinite(options.missing_marker_weight))
    throw std::invalid_argument("fill_gloersen_pca: missing_marker_weight must be positive");
  if (!(options.distal_threshold > 0.0) || !std::isfinite(options.distal_threshold))
    throw std::invalid_argument("fill_gloersen_pca: distal_threshold must be positive");
  // All components (1.0) would make the projection the identity: the zeroed target stays zero.
  if (!(options.min_cumulative_singular_values > 0.0 && options.min_cumulative_singular_values < 1.0))
    throw std::invalid_argument("fill_gloersen_pca: min_cumulative_singular_values must be in (0, 1)");
  if (options.min_training_frames < 2)
    throw std::invalid_argument("fill_gloersen_pca: min_training_frames must be at least 2");
}

// The labelled, at-least-once-present channels as a frames x markers table.
struct MarkerTable {
  std::vector<int> channels;  // capture channel of each marker
  int frames = 0;
  std::vector<char> present;   // frame-major, frames x markers
  std::vector<Vec3> position;  // frame-major; NaN when absent
  std::vector<char> has_gap;   // per marker
  bool any_gap_free = false;
  std::vector<Vec3> centre;  // per frame, see moving_centre(); NaN when no marker is present
  int markers() const { return static_cast<int>(channels.size()); }
  bool is_present(int f, int j) const { return present[static_cast<size_t>(f) * channels.size() + j]; }
  const Vec3& at(int f, int j) const { return position[static_cast<size_t>(f) * channels.size() + j]; }
};

// The capture-wide moving frame: the published mean of the gap-free markers or, when every
// marker has a gap, the centroid of the additive fit p_j(f) ~ c(f) + o_j over present samples.
std::vector<Vec3> moving_centre(const MarkerTable& table) {
  const int frames = table.frames, markers = table.markers();
  std::vector<Vec3> centre(frames, missing_point());
  if (table.any_gap_free) {
    for (int f = 0; f < frames; ++f) {
      Vec3 sum = Vec3::Zero();
      int count = 0;
      for (int j = 0; j < markers; ++j)
        if (!table.has_gap[j]) sum += table.at(f, j), ++count;
      centre[f] = sum / count;
    }
    return centre;
  }
  std::vector<Vec3> offset(markers, Vec3::Zero());
  for (int round = 0; round < 5; ++round) {
    for (int f = 0; f < frames; ++f) {
      Vec3 sum = Vec3::Zero();
      int count = 0;
      for (int j = 0; j < markers; ++j)
        if (table.is_present(f, j)) sum += table.at(f, j) - offset[j], ++count;
      centre[f] = count ? Vec3(sum / count) : missing_point();
    }
    for (int j = 0; j < markers; ++j) {
      Vec3 sum = Vec3::Zero();
      int count = 0;
      for (int f = 0; f < frames; ++f)
        if (table.is_present(f, j)) sum += table.at(f, j) - centre[f], ++count;
      offset[j] = sum / count;  // every marker is present at least once
    }
  }
  return centre;
}

MarkerTable build_table(const Capture& capture) {
  MarkerTable table;
  table.frames = capture.frame_count;
  for (int point : capture.labelled_points()) {
    bool ever = false;
    for (int f = 0; f < capture.frame_count && !ever; ++f) ever = capture.present(f, point);
    if (ever) table.channels.push_back(point);
  }
  const int markers = table.markers();
  table.present.resize(static_cast<size_t>(table.frames) * markers);
  table.position.resize(table.present.size());
  table.has_gap.assign(markers, 0);
  for (int f = 0; f < table.frames; ++f)
    for (int j = 0; j < markers; ++j) {
      const size_t at = static_cast<size_t>(f) * markers + j;
      table.position[at] = capture.at(f, table.channels[j]);
      table.present[at] = is_present(table.position[at]);
      if (!table.present[at]) table.has_gap[j] = 1, table.position[at] = missing_point();
    }
  table.any_gap_free = std::find(table.has_gap.begin(), table.has_gap.end(), 0) != table.has_gap.end();
  table.centre = moving_centre(table);
  return table;
}

// Mean over frames where both are present of |p_i - p_j|; infinity when never together.
std::vector<double> mean_distances_from(const MarkerTable& table, int i) {
  std::vector<double> distance(table.markers(), std::numeric_limits<double>::infinity());
  for (int j = 0; j < table.markers(); ++j) {
    double sum = 0.0;
    int count = 0;
    for (int f = 0; f < table.frames; ++f)
      if (table.is_present(f, i) && table.is_present(f, j))
        sum += (table.at(f, i) - table.at(f, j)).norm(), ++count;
    if (count) distance[j] = sum / count;
  }
  return distance;
}

// Principal directions (columns, by decreasing variance) and singular values of a covariance.
struct Components {
  Eigen::MatrixXd directions;
  Eigen::VectorXd singular_values;
};

Components principal_components(const Eigen::MatrixXd& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  const Eigen::Index n = covariance.rows();
  Components out{solver.eigenvectors().rowwise().reverse(), solver.eigenvalues().reverse()};
  for (Eigen::Index k = 0; k < n; ++k)
    out.singular_values(k) = std::sqrt(std::max(0.0, out.singular_values(k)));
  return out;
}

// Fewest leading components whose singular values reach `share` of their sum.
Eigen::Index components_needed(const Eigen::VectorXd& singular_values, double share) {
  const double total = singular_values.sum();
  if (!(total > 0.0)) return 0;
  double running = 0.0;
  for (Eigen::Index k = 0; k < singular_values.size(); ++k) {
    running += singular_values(k);
    if (running >= share * total) return k + 1;
  }
  return singular_values.size();
}

// R2's marker selection for filling `target` at `frames`: the target, every gap-free marker, and
// each marker with gaps that is near the target and present at all of those frames.
std::vector<int> model_markers(const MarkerTable& table, int target, const std::vector<int>& frames,
                               const std::vector<double>& distance, double distal) {
  std::vector<int> kept = {target};
  for (int j = 0; j < table.markers(); ++j) {
    if (j == target) continue;
    if (table.has_gap[j]) {
      if (!(distance[j] <= distal)) continue;
      if (std::any_of(frames.begin(), frames.end(), [&](int f) { return !table.is_present(f, j); })) continue;
    }
    kept.push_back(j);
  }
  return kept;
}

// Fills the target (kept[0]) at `to_fill` into `out` with the PCA model of the markers `kept`,
// trained on every frame where all of them are present.
void fill_with_model(const MarkerTable& table, const std::vector<int>& kept, const std::vector<int>& to_fill,
                     const std::vector<double>& distance, const GloersenOptions& options, Capture& out) {
  const int target = kept.front();
  std::vector<int> training;
  for (int f = 0; f < table.frames; ++f)
    if (std::all_of(kept.begin(), kept.end(), [&](int j) { return table.is_present(f, j); }))
      training.push_back(f);
  if (static_cast<int>(training.size()) < options.min_training_frames) return;

  // The moving frame must be the same function of the data in training and gap rows: the
  // capture-wide one when gap-free markers define it, else the mean of the model's other markers,
  // which are present in every row of this model.
  const bool own_centre = !table.any_gap_free && kept.size() > 1;
  auto centre_at = [&](int f) -> Vec3 {
    if (!own_centre) return table.centre[f];
    Vec3 sum = Vec3::Zero();
    for (size_t k = 1; k < kept.size(); ++k) sum += table.at(f, kept[k]);
    return sum / static_cast<double>(kept.size() - 1);
  };
  const Eigen::Index columns = 3 * static_cast<Eigen::Index>(kept.size());
  auto rows_of = [&](const std::vector<int>& frames) {
    Eigen::MatrixXd rows(static_cast<Eigen::Index>(frames.size()), columns);
    for (size_t r = 0; r < frames.size(); ++r) {
      const Vec3 centre = centre_at(frames[r]);
      for (size_t k = 0; k < kept.size(); ++k)
        rows.block<1, 3>(static_cast<Eigen::Index>(r), 3 * static_cast<Eigen::Index>(k)) =
            (table.at(frames[r], kept[k]) - centre).transpose();
    }
    return rows;
  };
  Eigen::MatrixXd train = rows_of(training);

  // Normalise to unit variance over the training frames, then weight by closeness to the target.
  const Eigen::RowVectorXd mean = train.colwise().mean();
  train.rowwise() -= mean;
  Eigen::RowVectorXd scale = (train.colwise().squaredNorm() / static_cast<double>(train.rows())).cwiseSqrt();
  for (Eigen::Index c = 0; c < columns; ++c)
    if (!(scale(c) > 0.0)) scale(c) = 1.0;
  Eigen::RowVectorXd weight(columns);
  for (size_t k = 0; k < kept.size(); ++k) {
    const double d = distance[kept[k]];
    const double w = k == 0 ? options.missing_marker_weight
                            : std::exp(-d * d / (2.0 * options.weight_scale_mm * options.weight_scale_mm));
    weight.segment<3>(3 * static_cast<Eigen::Index>(k)).setConstant(w);
  }
  const Eigen::RowVectorXd factor = weight.cwiseQuotient(scale);
  train.array().rowwise() *= factor.array();

  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(columns, columns);
  covariance.selfadjointView<Eigen::Lower>().rankUpdate(train.transpose(), 1.0 / (train.rows() - 1));
  covariance = covariance.selfadjointView<Eigen::Lower>();
  Eigen::MatrixXd covariance_zeroed = covariance;  // covariance of N0: the target's columns zeroed
  covariance_zeroed.topRows<3>().setZero();
  covariance_zeroed.leftCols<3>().setZero();

  const Components complete = principal_components(covariance);
  const Components incomplete = principal_components(covariance_zeroed);
  const Eigen::Index kept_components =
      std::max(components_needed(complete.singular_values, options.min_cumulative_singular_values),
               components_needed(incomplete.singular_values, options.min_cumulative_singular_values));
  const Eigen::MatrixXd v = complete.directions.leftCols(kept_components);
  const Eigen::MatrixXd v0 = incomplete.directions.leftCols(kept_components);

  Eigen::MatrixXd gapped = rows_of(to_fill);  // target columns are NaN: zero them after normalising
  gapped.rowwise() -= mean;
  gapped.array().rowwise() *= factor.array();
  gapped.leftCols<3>().setZero();
  // Federolf 2013: scores in the incomplete basis, through T = V'V0 into the complete basis,
  // read off at the target's columns.
  const Eigen::MatrixXd transformation = v.transpose() * v0;
  const Eigen::MatrixXd reconstructed = (gapped * v0) * transformation * v.topRows<3>().transpose();

  for (size_t r = 0; r < to_fill.size(); ++r) {
    const Eigen::Index row = static_cast<Eigen::Index>(r);
    const Eigen::RowVector3d value = mean.head<3>() + reconstructed.row(row).cwiseQuotient(factor.head<3>());
    out.at(to_fill[r], table.channels[target]) = value.transpose() + centre_at(to_fill[r]);
  }
}

}  // namespace

Capture fill_gloersen_pca(const Capture& capture, const GloersenOptions& options) {
  validate(capture, options);
  Capture out = capture;
  const MarkerTable table = build_table(capture);

  for (int target = 0; target < table.markers(); ++target) {
    if (!table.has_gap[target]) continue;
    std::vector<int> to_fill;
    for (int f = 0; f < table.frames; ++f)
      if (!table.is_present(f, target) && is_present(table.centre[f])) to_fill.push_back(f);
    if (to_fill.empty()) continue;

    const std::vector<double> distance = mean_distances_from(table, target);
    double distance_sum = 0.0;
    int finite = 0;
    for (double d : distance)
      if (std::isfinite(d)) distance_sum += d, ++finite;
    const double distal = options.distal_threshold * distance_sum / std::max(finite, 1);

    // Runs of consecutive frames to fill; per_marker treats all of them as one.
    std::vector<std::vector<int>> runs;
    for (size_t begin = 0; begin < to_fill.size();) {
      size_t end = begin + 1;
      while (options.grouping == GloersenGrouping::per_marker
                 ? end < to_fill.size()
                 : end < to_fill.size() && to_fill[end] == to_fill[end - 1] + 1)
        ++end;
      runs.emplace_back(to_fill.begin() + begin, to_fill.begin() + end);
      begin = end;
    }
    // Runs that select the same markers get the same model: train it once.
    std::map<std::vector<int>, std::vector<int>> frames_by_markers;
    for (const std::vector<int>& run : runs) {
      std::vector<int>& frames = frames_by_markers[model_markers(table, target, run, distance, distal)];
      frames.insert(frames.end(), run.begin(), run.end());
    }
    for (const auto& [kept, frames] : frames_by_markers)
      fill_with_model(table, kept, frames, distance, options, out);
  }
  return out;
}

}  // namespace skinstream
