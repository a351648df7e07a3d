#include "core/offline/marker_surface_builder.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <unordered_map>

namespace skinstream {
namespace {

using Triangle = std::array<int, 3>;

uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | static_cast<uint32_t>(b);
}

double min_angle_degrees(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto angle = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    const Vec3 u = (q - p).normalized(), v = (r - p).normalized();
    return std::acos(std::clamp(u.dot(v), -1.0, 1.0)) * 180.0 / M_PI;
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Direction from the edge (a, b) towards the third vertex, perpendicular to the edge.
Vec3 wing(const Vec3& a, const Vec3& b, const Vec3& third) {
  const Vec3 e = (b - a).normalized();
  const Vec3 v = third - a;
  return (v - v.dot(e) * e).normalized();
}

// Orients triangles consistently across shared edges (breadth first), then per connected
// piece flips all so that most normals point away from the piece's centroid.
void orient_triangles(const std::vector<Vec3>& x, std::vector<Triangle>& tris) {
  std::unordered_map<uint64_t, std::vector<int>> by_edge;
  for (int t = 0; t < static_cast<int>(tris.size()); ++t)
    for (int e = 0; e < 3; ++e) by_edge[edge_key(tris[t][e], tris[t][(e + 1) % 3])].push_back(t);
  std::vector<int> piece(tris.size(), -1);
  int pieces = 0;
  for (int seed = 0; seed < static_cast<int>(tris.size()); ++seed) {
    if (piece[seed] >= 0) continue;
    std::vector<int> members;
    std::queue<int> todo;
    todo.push(seed);
    piece[seed] = pieces;
    while (!todo.empty()) {
      const int t = todo.front();
      todo.pop();
      members.push_back(t);
      for (int e = 0; e < 3; ++e) {
        const int a = tris[t][e], b = tris[t][(e + 1) % 3];
        for (int u : by_edge[edge_key(a, b)]) {
          if (u == t || piece[u] >= 0) continue;
          // Consistent orientation: the neighbour must traverse the shared edge as b -> a.
          bool same_direction = false;
          for (int f = 0; f < 3; ++f)
            if (tris[u][f] == a && tris[u][(f + 1) % 3] == b) same_direction = true;
          if (same_direction) std::swap(tris[u][1], tris[u][2]);
          piece[u] = pieces;
          todo.push(u);
        }
      }
    }
    Vec3 centroid = Vec3::Zero();
    for (int t : members) centroid += (x[tris[t][0]] + x[tris[t][1]] + x[tris[t][2]]) / 3.0;
    centroid /= static_cast<double>(members.size());
    double vote = 0.0;
    for (int t : members) {
      const Vec3& a = x[tris[t][0]];
      const Vec3 n = (x[tris[t][1]] - a).cross(x[tris[t][2]] - a);
      vote += n.dot((a + x[tris[t][1]] + x[tris[t][2]]) / 3.0 - centroid) > 0 ? 1.0 : -1.0;
    }
    if (vote < 0)
      for (int t : members) std::swap(tris[t][1], tris[t][2]);
    ++pieces;
  }
}

MarkerSurface finish_surface(const std::vector<Vec3>& x, std::vector<Triangle> tris, const Eigen::MatrixXd& skin,
                             int max_ring) {
  const int n = static_cast<int>(x.size());
  orient_triangles(x, tris);
  MarkerSurface s;
  s.rings = triangle_neighbours(tris, n);
  s.normals.assign(n, Vec3::Zero());
  for (const Triangle& t : tris) {
    const Vec3 area_normal = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    for (int e = 0; e < 3; ++e) s.normals[t[e]] += area_normal;
  }
  for (int i = 0; i < n; ++i) {
    std::vector<int>& ring = s.rings[i];
    auto nearer = [&](int a, int b) { return skin(i, a) < skin(i, b); };
    if (static_cast<int>(ring.size()) < 3) {
      ++s.markers_given_extra_neighbours;
      std::vector<int> order(n);
      std::iota(order.begin(), order.end(), 0);
      std::sort(order.begin(), order.end(), nearer);
      for (int j : order) {
        if (static_cast<int>(ring.size()) >= 3) break;
        if (j == i || !std::isfinite(skin(i, j)) || std::find(ring.begin(), ring.end(), j) != ring.end()) continue;
        ring.push_back(j);
      }
    }
    std::sort(ring.begin(), ring.end(), nearer);
    if (static_cast<int>(ring.size()) > max_ring) ring.resize(max_ring);

    if (s.normals[i].norm() > 1e-12) {
      s.normals[i].normalize();
    } else {
      // No triangle: the normal of the plane through the ring, pointing away from it.
      Vec3 c = Vec3::Zero();
      for (int j : ring) c += x[j];
      c /= std::max<size_t>(1, ring.size());
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int j : ring) cov += (x[j] - c) * (x[j] - c).transpose();
      Vec3 nrm = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
      if (nrm.dot(x[i] - c) < 0) nrm = -nrm;
      s.normals[i] = nrm.normalized();
    }
  }
  s.triangles = std::move(tris);
  return s;
}

}  // namespace

std::vector<std::vector<int>> triangle_neighbours(std::span<const std::array<int, 3>> triangles, int marker_count) {
  std::vector<std::vector<int>> neighbours(marker_count);
  for (const auto& t : triangles)
    for (int e = 0; e < 3; ++e)
      for (int f = 0; f < 3; ++f)
        if (f != e) neighbours[t[e]].push_back(t[f]);
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return neighbours;
}

MarkerSurface build_marker_surface(const std::vector<Vec3>& x, const Eigen::MatrixXd& skin,
                                   const MarkerSurfaceOptions& options) {
  const int n = static_cast<int>(x.size());
  // Candidate edges: each marker to its k nearest by skin distance (either direction).
  std::vector<std::vector<char>> edge(n, std::vector<char>(n, 0));
  for (int i = 0; i < n; ++i) {
    std::vector<int> order;
    for (int j = 0; j < n; ++j)
      if (j != i && std::isfinite(skin(i, j))) order.push_back(j);
    const int k = std::min<int>(options.candidate_neighbours, static_cast<int>(order.size()));
    std::partial_sort(order.begin(), order.begin() + k, order.end(),
                      [&](int a, int b) { return skin(i, a) < skin(i, b); });
    for (int m = 0; m < k; ++m) edge[i][order[m]] = edge[order[m]][i] = 1;
  }

  struct Candidate {
    Triangle t;
    double cost;
  };
  std::vector<Candidate> candidates;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (!edge[a][b]) continue;
      for (int c = b + 1; c < n; ++c)
        if (edge[a][c] && edge[b][c]) candidates.push_back({{a, b, c}, skin(a, b) + skin(b, c) + skin(a, c)});
    }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& p, const Candidate& q) { return p.cost < q.cost; });

  std::unordered_map<uint64_t, std::vector<int>> used;  // edge -> third vertices of its triangles
  std::vector<Triangle> accepted;
  for (const Candidate& cand : candidates) {
    const Triangle& t = cand.t;
    if (min_angle_degrees(x[t[0]], x[t[1]], x[t[2]]) < options.min_angle_degrees) continue;
    bool ok = true;
    for (int e = 0; e < 3 && ok; ++e) {
      const int a = t[e], b = t[(e + 1) % 3], third = t[(e + 2) % 3];
      const auto it = used.find(edge_key(a, b));
      if (it == used.end()) continue;
      if (it->second.size() >= 2) ok = false;
      // The new triangle must lie on the other side of the edge, not fold over the old one.
      for (int other : it->second)
        if (wing(x[a], x[b], x[third]).dot(wing(x[a], x[b], x[other])) > 0.5) ok = false;
    }
    if (!ok) continue;
    accepted.push_back(t);
    for (int e = 0; e < 3; ++e) used[edge_key(t[e], t[(e + 1) % 3])].push_back(t[(e + 2) % 3]);
  }
  return finish_surface(x, std::move(accepted), skin, options.max_ring);
}

MarkerSurface marker_surface_from_triangles(const std::vector<Vec3>& reference,
                                            const std::vector<std::array<int, 3>>& triangles,
                                            const Eigen::MatrixXd& skin_distance, int max_ring) {
  return finish_surface(reference, triangles, skin_distance, max_ring);
}

}  // namespace skinstream
