#include "core/geometry/triangle_bvh.h"

#include <Eigen/Geometry>  // cross()
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace skinstream {

namespace {

constexpr int kLeafSize = 4;
// Barycentric slack of ray casts: a ray along the body's symmetry plane runs through the edges
// of the seam there; rounding must not let it pass between the triangles.
constexpr double kEdgeSlack = 1e-9;

// Moller-Trumbore: distance along the unit direction to the triangle, or +inf; the crossing's
// barycentric weights of b and c when asked. `slack` widens the triangle by that much in
// barycentric terms, so that a ray through a shared edge cannot slip between its two triangles.
double ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c,
                    double* out_u = nullptr, double* out_v = nullptr, double slack = 0.0) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-12) return std::numeric_limits<double>::infinity();
  const double inv = 1.0 / det;
  const Vec3 s = o - a;
  const double u = s.dot(p) * inv;
  if (u < -slack || u > 1.0 + slack) return std::numeric_limits<double>::infinity();
  const Vec3 q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < -slack || u + v > 1.0 + slack) return std::numeric_limits<double>::infinity();
  if (out_u) *out_u = u;
  if (out_v) *out_v = v;
  return e2.dot(q) * inv;
}

bool ray_box(const Vec3& o, const Vec3& inv_d, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
             double t0, double t1) {
  for (int k = 0; k < 3; ++k) {
    double a = (lo[k] - o[k]) * inv_d[k];
    double b = (hi[k] - o[k]) * inv_d[k];
    if (a > b) std::swap(a, b);
    if (std::isnan(a) || std::isnan(b)) {  // direction 0 on this axis, origin on a slab plane
      if (o[k] < lo[k] || o[k] > hi[k]) return false;
      continue;
    }
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

double box_distance2(const Vec3& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double e = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
    d2 += e * e;
  }
  return d2;
}

}  // namespace

TriangleBvh::TriangleBvh(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles)
    : points_(points), triangles_(triangles) {
  for (const Triangle& t : triangles_)
    for (int i : t)
      if (i < 0 || i >= static_cast<int>(points_.size()))
        throw std::invalid_argument("TriangleBvh: triangle vertex " + std::to_string(i) + " of " +
                                    std::to_string(points_.size()));
  order_.resize(triangles_.size());
  std::vector<Vec3> centroids(triangles_.size());
  for (size_t i = 0; i < triangles_.size(); ++i) {
    order_[i] = static_cast<int>(i);
    const Triangle& t = triangles_[i];
    centroids[i] = (points_[static_cast<size_t>(t[0])] + points_[static_cast<size_t>(t[1])] +
                    points_[static_cast<size_t>(t[2])]) /
                   3.0;
  }
  nodes_.reserve(2 * triangles_.size() / kLeafSize + 2);
  if (!triangles_.empty()) build(0, static_cast<int>(triangles_.size()), centroids);
  points_.clear();
  points_.shrink_to_fit();
  refit(points);
}

int TriangleBvh::build(int begin, int end, std::vector<Vec3>& centroids) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{});
  if (end - begin <= kLeafSize) {
    nodes_[static_cast<size_t>(index)].first = begin;
    nodes_[static_cast<size_t>(index)].count = end - begin;
    return index;
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (int i = begin; i < end; ++i) {
    lo = lo.cwiseMin(centroids[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
    hi = hi.cwiseMax(centroids[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](int a, int b) {
    return centroids[static_cast<size_t>(a)][axis] < centroids[static_cast<size_t>(b)][axis];
  });
  build(begin, mid, centroids);
  const int right = build(mid, end, centroids);
  nodes_[static_cast<size_t>(index)].first = right;
  nodes_[static_cast<size_t>(index)].count = 0;
  return index;
}

void TriangleBvh::refit(const std::vector<Vec3>& points) {
  points_ = points;
  for (const Triangle& t : triangles_)
    for (int i : t)
      if (i >= static_cast<int>(points_.size()))
        throw std::invalid_argument("TriangleBvh::refit: fewer points than the mesh uses");
  if (!nodes_.empty()) refit_node(0);
}

void TriangleBvh::refit_node(int index) {
  Node& n = nodes_[static_cast<size_t>(index)];
  if (n.count > 0) {
    n.lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    n.hi = -n.lo;
    for (int i = n.first; i < n.first + n.count; ++i)
      for (int v : triangles_[static_cast<size_t>(order_[static_cast<size_t>(i)])]) {
        n.lo = n.lo.cwiseMin(points_[static_cast<size_t>(v)]);
        n.hi = n.hi.cwiseMax(points_[static_cast<size_t>(v)]);
      }
    return;
  }
  const int left = index + 1, right = n.first;
  refit_node(left);
  refit_node(right);
  Node& m = nodes_[static_cast<size_t>(index)];
  m.lo = nodes_[static_cast<size_t>(left)].lo.cwiseMin(nodes_[static_cast<size_t>(right)].lo);
  m.hi = nodes_[static_cast<size_t>(left)].hi.cwiseMax(nodes_[static_cast<size_t>(right)].hi);
}

bool TriangleBvh::segment_blocked(const Vec3& from, const Vec3& to, double skip_mm) const {
  if (nodes_.empty()) return false;
  const Vec3 delta = to - from;
  const double length = delta.norm();
  if (length <= 2.0 * skip_mm) return false;
  const Vec3 d = delta / length;
  const Vec3 inv_d(1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z());
  const double t0 = skip_mm, t1 = length - skip_mm;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int index = stack[--top];
    const Node& n = nodes_[static_cast<size_t>(index)];
    if (!ray_box(from, inv_d, n.lo, n.hi, t0, t1)) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const Triangle& t = triangles_[static_cast<size_t>(order_[static_cast<size_t>(i)])];
        const double hit =
            ray_triangle(from, d, points_[static_cast<size_t>(t[0])], points_[static_cast<size_t>(t[1])],
                         points_[static_cast<size_t>(t[2])]);
        if (hit > t0 && hit < t1) return true;
      }
    } else if (top + 2 <= 128) {
      stack[top++] = n.first;
      stack[top++] = index + 1;
    }
  }
  return false;
}

std::vector<RayHit> TriangleBvh::ray_hits(const Vec3& origin, const Vec3& direction,
                                          double max_distance) const {
  const double length = direction.norm();
  if (!is_present(origin) || !std::isfinite(length) || length == 0.0)
    throw std::invalid_argument(
        "TriangleBvh::ray_hits: the ray needs a finite origin and a non-zero direction");
  std::vector<RayHit> hits;
  if (nodes_.empty() || !(max_distance >= 0.0)) return hits;
  const Vec3 d = direction / length;
  const Vec3 inv_d(1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z());
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int index = stack[--top];
    const Node& n = nodes_[static_cast<size_t>(index)];
    if (!ray_box(origin, inv_d, n.lo, n.hi, 0.0, max_distance)) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int ti = order_[static_cast<size_t>(i)];
        const Triangle& t = triangles_[static_cast<size_t>(ti)];
        double u = 0.0, v = 0.0;
        const double hit =
            ray_triangle(origin, d, points_[static_cast<size_t>(t[0])], points_[static_cast<size_t>(t[1])],
                         points_[static_cast<size_t>(t[2])], &u, &v, kEdgeSlack);
        if (!(hit >= 0.0 && hit <= max_distance && std::isfinite(hit))) continue;
        // Back onto the triangle when the slack let the crossing fall just outside it.
        Vec3 w(1.0 - u - v, u, v);
        w = w.cwiseMax(0.0);
        hits.push_back({hit, ti, w / w.sum()});
      }
    } else if (top + 2 <= 128) {
      stack[top++] = n.first;
      stack[top++] = index + 1;
    }
  }
  std::sort(hits.begin(), hits.end(), [](const RayHit& a, const RayHit& b) {
    return a.distance < b.distance || (a.distance == b.distance && a.triangle < b.triangle);
  });
  return hits;
}

double TriangleBvh::closest(const Vec3& p, int* triangle, Vec3* point) const {
  double best2 = std::numeric_limits<double>::infinity();
  int best_t = -1;
  Vec3 best_p = Vec3::Zero();
  if (!nodes_.empty()) {
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const int index = stack[--top];
      const Node& n = nodes_[static_cast<size_t>(index)];
      if (box_distance2(p, n.lo, n.hi) >= best2) continue;
      if (n.count > 0) {
        for (int i = n.first; i < n.first + n.count; ++i) {
          const int ti = order_[static_cast<size_t>(i)];
          const Triangle& t = triangles_[static_cast<size_t>(ti)];
          const Vec3 q = closest_point_on_triangle(p, points_[static_cast<size_t>(t[0])],
                                                   points_[static_cast<size_t>(t[1])],
                                                   points_[static_cast<size_t>(t[2])]);
          const double d2 = (q - p).squaredNorm();
          if (d2 < best2) {
            best2 = d2;
            best_t = ti;
            best_p = q;
          }
        }
      } else if (top + 2 <= 128) {
        const int left = index + 1, right = n.first;
        const double dl =
            box_distance2(p, nodes_[static_cast<size_t>(left)].lo, nodes_[static_cast<size_t>(left)].hi);
        const double dr =
            box_distance2(p, nodes_[static_cast<size_t>(right)].lo, nodes_[static_cast<size_t>(right)].hi);
        if (dl < dr) {  // visit the nearer child first
          stack[top++] = right;
          stack[top++] = left;
        } else {
          stack[top++] = left;
          stack[top++] = right;
        }
      }
    }
  }
  if (triangle) *triangle = best_t;
  if (point) *point = best_p;
  return std::sqrt(best2);
}

bool TriangleBvh::boxes_overlap(int a, int b) const {
  const Node& x = nodes_[static_cast<size_t>(a)];
  const Node& y = nodes_[static_cast<size_t>(b)];
  return (x.lo.array() <= y.hi.array()).all() && (y.lo.array() <= x.hi.array()).all();
}

// The crossing pairs between the triangles of two leaves (or within one leaf when a == b).
void TriangleBvh::cross_leaves(int a, int b, std::vector<std::array<int, 2>>& out) const {
  const Node& x = nodes_[static_cast<size_t>(a)];
  const Node& y = nodes_[static_cast<size_t>(b)];
  for (int i = x.first; i < x.first + x.count; ++i) {
    const int ti = order_[static_cast<size_t>(i)];
    const Triangle& t = triangles_[static_cast<size_t>(ti)];
    for (int j = (a == b ? i + 1 : y.first); j < y.first + y.count; ++j) {
      const int tj = order_[static_cast<size_t>(j)];
      const Triangle& u = triangles_[static_cast<size_t>(tj)];
      bool shared = false;
      for (int p : t)
        for (int q : u) shared = shared || p == q;
      if (shared) continue;  // neighbours meet at their shared vertex or edge by construction
      const Vec3 &t0 = points_[static_cast<size_t>(t[0])], &t1 = points_[static_cast<size_t>(t[1])],
                 &t2 = points_[static_cast<size_t>(t[2])];
      const Vec3 &u0 = points_[static_cast<size_t>(u[0])], &u1 = points_[static_cast<size_t>(u[1])],
                 &u2 = points_[static_cast<size_t>(u[2])];
      // Box of each triangle first: most pairs of two overlapping leaves are apart.
      const Eigen::Vector3d tlo = t0.cwiseMin(t1).cwiseMin(t2), thi = t0.cwiseMax(t1).cwiseMax(t2);
      const Eigen::Vector3d ulo = u0.cwiseMin(u1).cwiseMin(u2), uhi = u0.cwiseMax(u1).cwiseMax(u2);
      if ((tlo.array() > uhi.array()).any() || (ulo.array() > thi.array()).any()) continue;
      if (triangles_cross(t0, t1, t2, u0, u1, u2)) out.push_back({std::min(ti, tj), std::max(ti, tj)});
    }
  }
}

std::vector<std::array<int, 2>> TriangleBvh::self_intersections() const {
  std::vector<std::array<int, 2>> out;
  if (nodes_.empty()) return out;
  // Pairs of nodes whose triangles may cross, a node paired with itself for the pairs inside it.
  std::vector<std::array<int, 2>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const Node& x = nodes_[static_cast<size_t>(a)];
    const Node& y = nodes_[static_cast<size_t>(b)];
    if (a == b) {
      if (x.count > 0) {
        cross_leaves(a, a, out);
      } else {
        stack.push_back({a + 1, a + 1});
        stack.push_back({x.first, x.first});
        stack.push_back({a + 1, x.first});
      }
      continue;
    }
    if (!boxes_overlap(a, b)) continue;
    if (x.count > 0 && y.count > 0) {
      cross_leaves(a, b, out);
    } else if (y.count > 0 || (x.count == 0 && (x.hi - x.lo).squaredNorm() >= (y.hi - y.lo).squaredNorm())) {
      stack.push_back({a + 1, b});  // split the larger inner node
      stack.push_back({x.first, b});
    } else {
      stack.push_back({a, b + 1});
      stack.push_back({a, y.first});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace skinstream
