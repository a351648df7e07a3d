#include "core/baselines/bone_heat_weights.h"

#include <Eigen/Geometry>  // cross()
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/geometry/triangle_bvh.h"

namespace skinstream {
namespace {

Vec3 closest_on_bone(const HeatBone& bone, const Vec3& p) {
  const Vec3 axis = bone.tail - bone.head;
  const double length2 = axis.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - bone.head).dot(axis) / length2, 0.0, 1.0) : 0.0;
  return bone.head + t * axis;
}

// Cotangent stiffness (positive semi-definite) and lumped vertex areas.
void cotangent_laplacian(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                         std::vector<Eigen::Triplet<double>>& out_stiffness, std::vector<double>& out_area) {
  out_area.assign(vertices.size(), 0.0);
  for (const Triangle& t : triangles) {
    const double doubled_area = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
    if (!(doubled_area > 0.0)) continue;  // degenerate: no angle to speak of
    for (int corner = 0; corner < 3; ++corner) {
      const int a = t[corner], b = t[(corner + 1) % 3], c = t[(corner + 2) % 3];
      out_area[a] += doubled_area / 6.0;
      // The angle at a weighs the opposite edge (b, c): half its cotangent.
      const double weight = 0.5 * (vertices[b] - vertices[a]).dot(vertices[c] - vertices[a]) / doubled_area;
      out_stiffness.emplace_back(b, c, -weight);
      out_stiffness.emplace_back(c, b, -weight);
      out_stiffness.emplace_back(b, b, weight);
      out_stiffness.emplace_back(c, c, weight);
    }
  }
}

}  // namespace

void bone_heat_weights(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                       const std::vector<HeatBone>& bones, int group_count, const BoneHeatOptions& options,
                       std::vector<int>& out_offsets, std::vector<PartInfluence>& out_weights) {
  if (bones.empty()) throw std::invalid_argument("bone_heat_weights: no bones");
  for (const HeatBone& b : bones)
    if (b.group < 0 || b.group >= group_count)
      throw std::invalid_argument("bone_heat_weights: bone group " + std::to_string(b.group) + " outside [0, " +
                                  std::to_string(group_count) + ")");
  const int n = static_cast<int>(vertices.size());
  for (const Triangle& t : triangles)
    for (int v : t)
      if (v < 0 || v >= n) throw std::invalid_argument("bone_heat_weights: triangle index out of range");

  // Heat sources: each vertex's nearest bone it can see, and its distance.
  const TriangleBvh bvh(vertices, triangles);
  Eigen::VectorXd heat = Eigen::VectorXd::Zero(n);    // H_jj
  Eigen::MatrixXd source = Eigen::MatrixXd::Zero(n, group_count);  // p, per group
  std::vector<std::pair<double, int>> by_distance(bones.size());
  for (int v = 0; v < n; ++v) {
    for (size_t b = 0; b < bones.size(); ++b)
      by_distance[b] = {(closest_on_bone(bones[b], vertices[v]) - vertices[v]).norm(), static_cast<int>(b)};
    std::sort(by_distance.begin(), by_distance.end());
    auto visible = [&](int b) {
      return !bvh.segment_blocked(vertices[v], closest_on_bone(bones[b], vertices[v]), options.surface_skip);
    };
    size_t first = 0;
    while (first < by_distance.size() && !visible(by_distance[first].second)) ++first;
    if (first == by_distance.size()) first = 0;  // sees no bone: its nearest anyway
    const double nearest = std::max(by_distance[first].first, 1e-9);
    // Bones as near (they meet at the same joint) share the vertex.
    std::vector<int> tied = {by_distance[first].second};
    for (size_t k = first + 1; k < by_distance.size() && by_distance[k].first <= nearest * (1.0 + 1e-4); ++k)
      if (visible(by_distance[k].second)) tied.push_back(by_distance[k].second);
    for (int b : tied) source(v, bones[b].group) += 1.0 / static_cast<double>(tied.size());
    heat(v) = options.heat_constant / (nearest * nearest);
  }

  // (L + A H) w = A H p: the equilibrium above multiplied through by the vertex areas.
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<double> area;
  cotangent_laplacian(vertices, triangles, entries, area);
  for (int v = 0; v < n; ++v) {
    heat(v) *= std::max(area[v], 1e-12);  // a vertex in no triangle still gets its bone
    entries.emplace_back(v, v, heat(v));
  }
  Eigen::SparseMatrix<double> system(n, n);
  system.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
  if (solver.info() != Eigen::Success) throw std::runtime_error("bone_heat_weights: the heat system is singular");
  Eigen::MatrixXd weights(n, group_count);
  for (int g = 0; g < group_count; ++g) weights.col(g) = solver.solve(Eigen::VectorXd(heat.cwiseProduct(source.col(g))));

  out_offsets.assign(1, 0);
  out_weights.clear();
  for (int v = 0; v < n; ++v) {
    const size_t begin = out_weights.size();
    double kept = 0.0;
    for (int g = 0; g < group_count; ++g)
      if (weights(v, g) >= options.min_weight) {
        out_weights.push_back({g, weights(v, g)});
        kept += weights(v, g);
      }
    if (begin == out_weights.size()) {  // every weight tiny: its largest
      int best = 0;
      weights.row(v).maxCoeff(&best);
      out_weights.push_back({best, 1.0});
      kept = 1.0;
    }
    for (size_t k = begin; k < out_weights.size(); ++k) out_weights[k].weight /= kept;
    out_offsets.push_back(static_cast<int>(out_weights.size()));
  }
}

}  // namespace skinstream
