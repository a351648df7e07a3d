#pragma once
// A bounding volume hierarchy over a triangle mesh for the camera ray tests (is the segment from
// a marker to a camera blocked by the body?), ray casts (where does a ray from a bone leave the
// body?), closest-point queries and the surface's crossings of itself (the checks of a fitted
// body). Built once per topology; refit() updates the boxes when the mesh deforms (cheap, and
// exact: only traversal gets slower as the pose drifts from the one it was built in, so callers
// rebuild now and then).
#include <array>
#include <limits>
#include <vector>

#include "core/geometry/triangle_mesh.h"

namespace skinstream {

// Where a ray crosses a triangle: the distance along the unit direction (mm), the triangle and
// the crossing in its barycentric coordinates (weights of its vertices 0, 1, 2).
struct RayHit {
  double distance = 0.0;
  int triangle = -1;
  Vec3 barycentric = Vec3::Zero();
};

class TriangleBvh {
 public:
  TriangleBvh() = default;
  // Throws std::invalid_argument for a triangle index out of range.
  TriangleBvh(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles);

  void refit(const std::vector<Vec3>& points);  // same triangles, moved points

  // Whether a triangle crosses the segment from -> to, ignoring hits closer than skip_mm to
  // `from` (the marker's own surface) and closer than skip_mm to `to`.
  bool segment_blocked(const Vec3& from, const Vec3& to, double skip_mm = 0.0) const;

  // Every triangle the ray origin + t * direction crosses for 0 <= t <= max_distance, nearest
  // first (a ray through a shared edge or vertex may report each triangle there). `direction`
  // need not be unit; distances are along its unit vector. Throws std::invalid_argument for a
  // zero or non-finite direction or a non-finite origin.
  std::vector<RayHit> ray_hits(const Vec3& origin, const Vec3& direction,
                               double max_distance = std::numeric_limits<double>::infinity()) const;

  // Distance from p to the surface; the closest triangle and point when asked.
  double closest(const Vec3& p, int* triangle = nullptr, Vec3* point = nullptr) const;

  // Pairs {i, j}, i < j, of triangles that share no vertex and cross each other
  // (triangles_cross): where the surface passes through itself. Sorted.
  std::vector<std::array<int, 2>> self_intersections() const;

  int triangle_count() const { return static_cast<int>(triangles_.size()); }

 private:
  struct Node {
    Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
    int first = 0;  // leaf: first index into order_; inner: index of the right child (left is next)
    int count = 0;  // triangles in a leaf, 0 for an inner node
  };
  int build(int begin, int end, std::vector<Vec3>& centroids);
  void refit_node(int node);
  bool boxes_overlap(int a, int b) const;
  void cross_leaves(int a, int b, std::vector<std::array<int, 2>>& out) const;

  std::vector<Vec3> points_;
  std::vector<Triangle> triangles_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace skinstream
