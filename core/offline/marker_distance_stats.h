#pragma once
// Pairwise marker distance statistics over a training take. Markers on the same patch of skin
// keep their distance while the body moves; a hand passing a hip does not. The "skin distance"
// mean + k * stddev is what the marker surface and the hold anchors are built on, so that a
// triangulation never joins a hand to a hip even when they touch in the reference pose.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct MarkerDistanceStats {
  Eigen::MatrixXd mean;    // N x N, mm
  Eigen::MatrixXd stddev;  // N x N, mm
  Eigen::MatrixXi samples; // frames both markers were present

  // mean + k * stddev; pairs never seen together get +infinity.
  Eigen::MatrixXd skin_distance(double k = 2.0) const;
};

// `markers` are channel indices of `capture`; at most `max_frames` evenly spaced frames are used.
MarkerDistanceStats compute_marker_distance_stats(const Capture& capture, const std::vector<int>& markers,
                                                  int max_frames = 2000);

// Per marker, the distance to its nearest other marker among `positions` (mm); +infinity for a
// marker alone.
std::vector<double> nearest_marker_distances(std::span<const Vec3> positions);

// The median of nearest_marker_distances: the layout's typical spacing (mm). Throws
// std::invalid_argument for fewer than two markers.
double median_nearest_marker_distance(std::span<const Vec3> positions);

}  // namespace skinstream
