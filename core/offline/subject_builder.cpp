#include "core/offline/subject_builder.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "core/local_frame.h"
#include "core/offline/marker_distance_stats.h"

namespace skinstream {

int choose_reference_frame(const Capture& capture, const std::vector<int>& markers) {
  const int step = std::max(1, capture.frame_count / 400);
  int best = -1;
  double best_spread = -1.0;
  std::vector<Vec3> frame(markers.size());
  for (int f = 0; f < capture.frame_count; f += step) {
    bool complete = true;
    for (int m : markers) complete = complete && capture.present(f, m);
    if (!complete) continue;
    for (size_t i = 0; i < markers.size(); ++i) frame[i] = capture.at(f, markers[i]);
    double spread = 0.0;
    for (double nearest : nearest_marker_distances(frame)) spread += nearest;
    if (spread > best_spread) {
      best_spread = spread;
      best = f;
    }
  }
  if (best < 0 && step > 1) {  // the subsample missed the only complete frames
    for (int f = 0; f < capture.frame_count && best < 0; ++f) {
      bool complete = true;
      for (int m : markers) complete = complete && capture.present(f, m);
      if (complete) best = f;
    }
  }
  return best;
}

SubjectModel build_subject(const Capture& training, const SubjectBuildOptions& options,
                           const std::vector<std::array<int, 3>>* triangles, SubjectBuildReport* out_report) {
  const std::vector<int> channels = training.labelled_points();
  const int n = static_cast<int>(channels.size());
  if (n < 4) throw std::invalid_argument("need at least 4 labelled markers, capture has " + std::to_string(n));

  int ref = options.reference_frame;
  if (ref < 0) {
    ref = choose_reference_frame(training, channels);
    if (ref < 0) {
      int best_frame = 0, best_count = -1;
      for (int f = 0; f < training.frame_count; ++f) {
        int count = 0;
        for (int c : channels) count += training.present(f, c);
        if (count > best_count) best_count = count, best_frame = f;
      }
      throw std::invalid_argument("no frame has all " + std::to_string(n) + " labelled markers present (frame " +
                                  std::to_string(best_frame) + " has " + std::to_string(best_count) +
                                  "); the reference pose needs every marker: train on a take with one complete frame");
    }
  } else {
    if (ref >= training.frame_count) throw std::invalid_argument("reference frame " + std::to_string(ref) + " is past the end");
    for (int c : channels)
      if (!training.present(ref, c))
        throw std::invalid_argument("marker " + training.labels[c] + " is missing in reference frame " + std::to_string(ref));
  }

  SubjectModel model;
  model.parameters = options.parameters;
  for (int c : channels) {
    model.marker_names.push_back(training.labels[c]);
    model.reference_positions.push_back(training.at(ref, c));
  }

  const MarkerDistanceStats stats = compute_marker_distance_stats(training, channels);
  const Eigen::MatrixXd skin = stats.skin_distance();
  MarkerSurface surface;
  if (triangles) {
    for (const auto& t : *triangles)
      for (int v : t)
        if (v < 0 || v >= n) throw std::invalid_argument("marker surface triangle index " + std::to_string(v) + " out of range");
    surface = marker_surface_from_triangles(model.reference_positions, *triangles, skin, options.surface.max_ring);
  } else {
    surface = build_marker_surface(model.reference_positions, skin, options.surface);
  }
  model.triangles = surface.triangles;

  model.ring_offsets.push_back(0);
  std::vector<Vec3> ring_positions;
  for (int i = 0; i < n; ++i) {
    ring_positions.clear();
    for (int j : surface.rings[i]) ring_positions.push_back(model.reference_positions[j]);
    const Eigen::Matrix3d frame = local_reference_frame(model.reference_positions[i], surface.normals[i], ring_positions);
    model.local_reference_frames.push_back(frame);
    for (int j : surface.rings[i]) {
      model.ring.push_back(j);
      model.ring_local_reference.push_back(frame * (model.reference_positions[j] - model.reference_positions[i]));  // eq. 1
    }
    model.ring_offsets.push_back(static_cast<int>(model.ring.size()));
  }

  // Anchors: the markers whose distance to i varies least (most rigidly attached).
  model.anchor_offsets.push_back(0);
  for (int i = 0; i < n; ++i) {
    std::vector<int> order;
    for (int j = 0; j < n; ++j)
      if (j != i && stats.samples(i, j) > 0) order.push_back(j);
    auto steadier = [&](int a, int b) {
      return stats.stddev(i, a) + 0.05 * stats.mean(i, a) < stats.stddev(i, b) + 0.05 * stats.mean(i, b);
    };
    const int k = std::min<int>(options.anchors, static_cast<int>(order.size()));
    std::partial_sort(order.begin(), order.begin() + k, order.end(), steadier);
    model.anchors.insert(model.anchors.end(), order.begin(), order.begin() + k);
    model.anchor_offsets.push_back(static_cast<int>(model.anchors.size()));
  }

  SubjectBuildReport report;
  report.min_training_frames = std::numeric_limits<int>::max();
  for (int i = 0; i < n; ++i) {
    std::vector<int> ring_channels;
    for (int j : surface.rings[i]) ring_channels.push_back(channels[j]);
    const std::vector<Vec3> local(model.ring_local_reference.begin() + model.ring_offsets[i],
                                  model.ring_local_reference.begin() + model.ring_offsets[i + 1]);
    model.pca.push_back(train_marker_pca(training, channels[i], ring_channels, local, options.pca));
    const MarkerPcaModel& m = model.pca.back();
    if (m.training_frames == 0) report.markers_never_complete.push_back(model.marker_names[i]);
    report.min_training_frames = std::min(report.min_training_frames, m.training_frames);
    report.mean_pca_components += static_cast<double>(m.variance.size()) / n;
    report.mean_ring_size += static_cast<double>(surface.rings[i].size()) / n;
  }
  if (options.regions) {
    model.region_offsets.push_back(0);
    for (int i = 0; i < n; ++i) {
      const std::vector<int> region = marker_region(skin, i, options.region_pca.size);
      std::vector<int> region_channels;
      for (int j : region) region_channels.push_back(channels[j]);
      model.region.insert(model.region.end(), region.begin(), region.end());
      model.region_offsets.push_back(static_cast<int>(model.region.size()));
      model.region_pca.push_back(train_region_pca(training, region_channels, options.region_pca));
    }
  }
  report.reference_frame = ref;
  report.markers = n;
  report.triangles = static_cast<int>(surface.triangles.size());
  report.markers_given_extra_neighbours = surface.markers_given_extra_neighbours;
  if (out_report) *out_report = report;

  const std::string problem = model.validate();
  if (!problem.empty()) throw std::logic_error("built an inconsistent subject model: " + problem);
  return model;
}

}  // namespace skinstream
