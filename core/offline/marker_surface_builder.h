#pragma once
// Builds the marker surface (section 4.1) from the reference pose: a triangle mesh whose
// vertices are the markers, the one-ring of each marker and a normal per marker.
//
// How: candidate edges join each marker to its nearest markers by *skin distance* (mean + 2
// stddev of the pair's distance over the training take, see marker_distance_stats.h), so pairs
// that slide against each other (hand and hip) are far apart even when they touch. Triangles are
// the triples of candidate edges, accepted greedily from the shortest, while every edge keeps at
// most two triangles, no triangle is a sliver and no two triangles fold onto each other.
// A marker left with fewer than three neighbours is given its nearest markers by skin distance,
// so every marker can still be estimated (eq. 2 needs three).

#include <Eigen/Core>
#include <array>
#include <span>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct MarkerSurface {
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::vector<int>> rings;  // one-ring per marker, nearest first
  std::vector<Vec3> normals;            // unit, consistently oriented where the mesh is connected
  int markers_given_extra_neighbours = 0;  // had fewer than three surface neighbours
};

struct MarkerSurfaceOptions {
  int candidate_neighbours = 6;  // k of the k-nearest candidate edges
  int max_ring = 12;
  double min_angle_degrees = 12.0;
};

// Per marker (0..marker_count-1), the markers it shares a triangle with, ascending, each once.
// Indices must be in range (callers check).
std::vector<std::vector<int>> triangle_neighbours(std::span<const std::array<int, 3>> triangles, int marker_count);

// `skin_distance` is N x N (see MarkerDistanceStats::skin_distance); `reference` the pose.
MarkerSurface build_marker_surface(const std::vector<Vec3>& reference, const Eigen::MatrixXd& skin_distance,
                                   const MarkerSurfaceOptions& options = {});

// The same, from triangles a user supplied (e.g. edited in a modelling tool).
MarkerSurface marker_surface_from_triangles(const std::vector<Vec3>& reference,
                                            const std::vector<std::array<int, 3>>& triangles,
                                            const Eigen::MatrixXd& skin_distance, int max_ring = 12);

}  // namespace skinstream
