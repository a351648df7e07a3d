#include "core/fitting/surface_checks.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <stdexcept>

#include "core/geometry/triangle_bvh.h"
#include "core/offline/mesh_edges.h"

namespace skinstream {

namespace {

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, fmt, a, b, c);
  return buffer;
}

void validate(std::span<const Vec3> reference, std::span<const Vec3> vertices,
              std::span<const Triangle> triangles, const SurfaceCheckLimits& limits) {
  if (reference.size() != vertices.size())
    throw std::invalid_argument("check_surface: " + std::to_string(vertices.size()) +
                                " vertices against a reference of " + std::to_string(reference.size()));
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int i : triangles[t])
      if (i < 0 || static_cast<size_t>(i) >= reference.size())
        throw std::invalid_argument("check_surface: triangle " + std::to_string(t) + " uses vertex " +
                                    std::to_string(i) + " of " + std::to_string(reference.size()));
  for (size_t v = 0; v < reference.size(); ++v)
    if (!is_present(reference[v]))
      throw std::invalid_argument("check_surface: reference vertex " + std::to_string(v) + " is not finite");
  if (!(limits.max_strain > 1.0) || !(limits.max_edge_stretch > 1.0))
    throw std::invalid_argument("check_surface: strain limits must be above 1");
  if (!(limits.max_strained_fraction >= 0.0) || !(limits.max_flipped_fraction >= 0.0) ||
      !(limits.max_self_intersecting_fraction >= 0.0))
    throw std::invalid_argument("check_surface: limit fractions must be 0 or more");
}

void measure_strain(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                    std::span<const Triangle> triangles, const SurfaceCheckLimits& limits,
                    SurfaceCheck& out) {
  std::vector<double> ratios, lengths, reference_lengths;
  for (const auto& [a, b] : unique_edges(triangles)) {
    const double ref = (reference[static_cast<size_t>(a)] - reference[static_cast<size_t>(b)]).norm();
    if (ref > 0.0) {
      lengths.push_back((vertices[static_cast<size_t>(a)] - vertices[static_cast<size_t>(b)]).norm());
      ratios.push_back(lengths.back() / ref);
      reference_lengths.push_back(ref);
    }
  }
  out.edges = static_cast<int>(ratios.size());
  if (ratios.empty()) return;
  std::vector<double> sorted = ratios;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  out.scale = sorted[sorted.size() / 2];
  if (!(out.scale > 0.0)) {  // more than half the edges collapsed: everything is strained
    out.strained_edges = out.edges;
    out.strained_fraction = 1.0;
    out.max_strain = out.max_stretch = out.longest_stretched_edge = std::numeric_limits<double>::infinity();
    return;
  }
  // A shard is measured against a typical edge (the reference's median, scaled), not against
  // the edge's own rest length: the tiny edges of a crease (the armpit) stretch twenty times
  // under skinning and stay short.
  std::nth_element(reference_lengths.begin(), reference_lengths.begin() + static_cast<long>(reference_lengths.size() / 2),
                   reference_lengths.end());
  const double typical = out.scale * reference_lengths[reference_lengths.size() / 2];
  out.max_strain = 1.0;
  for (size_t e = 0; e < ratios.size(); ++e) {
    const double x = ratios[e] / out.scale;
    const double strain = x > 0.0 ? std::max(x, 1.0 / x) : std::numeric_limits<double>::infinity();
    out.max_strain = std::max(out.max_strain, strain);
    out.max_stretch = std::max(out.max_stretch, x);
    if (x > 1.0) out.longest_stretched_edge = std::max(out.longest_stretched_edge, lengths[e] / typical);
    out.strained_edges += strain > limits.max_strain;
  }
  out.strained_fraction = static_cast<double>(out.strained_edges) / static_cast<double>(out.edges);
}

// Flips: each triangle against the rotation of its neighbourhood (the vertices of every
// triangle that shares a vertex with it), fitted by least squares (Kabsch). A pose bends the
// surface smoothly, so a neighbourhood turns with the triangle; a triangle turned inside out
// against its neighbours is a fold.
int count_flips(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                std::span<const Triangle> triangles) {
  const size_t n = reference.size();
  std::vector<int> offsets(n + 1, 0), incident;
  for (const Triangle& t : triangles)
    for (int i : t) ++offsets[static_cast<size_t>(i) + 1];
  for (size_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  incident.resize(static_cast<size_t>(offsets[n]));
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int i : triangles[t])
      incident[static_cast<size_t>(fill[static_cast<size_t>(i)]++)] = static_cast<int>(t);

  std::vector<int> stamp(n, -1), ring;
  int flips = 0;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Triangle& tri = triangles[t];
    const Vec3 n_ref =
        triangle_normal(reference[static_cast<size_t>(tri[0])], reference[static_cast<size_t>(tri[1])],
                        reference[static_cast<size_t>(tri[2])]);
    if (n_ref.isZero()) continue;  // no orientation to keep
    const Vec3 n_new =
        triangle_normal(vertices[static_cast<size_t>(tri[0])], vertices[static_cast<size_t>(tri[1])],
                        vertices[static_cast<size_t>(tri[2])]);
    if (n_new.isZero()) {  // collapsed
      ++flips;
      continue;
    }
    ring.clear();
    for (int i : tri)
      for (int k = offsets[static_cast<size_t>(i)]; k < offsets[static_cast<size_t>(i) + 1]; ++k)
        for (int v : triangles[static_cast<size_t>(incident[static_cast<size_t>(k)])])
          if (stamp[static_cast<size_t>(v)] != static_cast<int>(t)) {
            stamp[static_cast<size_t>(v)] = static_cast<int>(t);
            ring.push_back(v);
          }
    Vec3 c_ref = Vec3::Zero(), c_new = Vec3::Zero();
    for (int v : ring) {
      c_ref += reference[static_cast<size_t>(v)];
      c_new += vertices[static_cast<size_t>(v)];
    }
    c_ref /= static_cast<double>(ring.size());
    c_new /= static_cast<double>(ring.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int v : ring)
      cov += (vertices[static_cast<size_t>(v)] - c_new) *
             (reference[static_cast<size_t>(v)] - c_ref).transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    const Eigen::Matrix3d rotation = svd.matrixU() * d * svd.matrixV().transpose();  // reference -> new
    flips += n_new.dot(rotation * n_ref) < 0.0;
  }
  return flips;
}

std::vector<std::array<int, 2>> crossings(std::span<const Vec3> points, std::span<const Triangle> triangles) {
  return TriangleBvh(std::vector<Vec3>(points.begin(), points.end()),
                     std::vector<Triangle>(triangles.begin(), triangles.end()))
      .self_intersections();
}

}  // namespace

SurfaceCheck check_surface(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                           std::span<const Triangle> triangles, const SurfaceCheckLimits& limits) {
  validate(reference, vertices, triangles, limits);
  SurfaceCheck out;
  const long non_finite =
      std::count_if(vertices.begin(), vertices.end(), [](const Vec3& p) { return !is_present(p); });
  if (non_finite > 0) {
    out.problem =
        std::to_string(non_finite) + " of " + std::to_string(vertices.size()) + " vertices are not finite";
    return out;
  }
  measure_strain(reference, vertices, triangles, limits, out);
  out.flipped_triangles = count_flips(reference, vertices, triangles);

  // A crossing is new when neither of its triangles crossed anything in the reference, nor shares
  // a vertex with one that did: where the template already passes through itself (its fingers,
  // its toes), a small move trades one crossing pair for its neighbour's, which is no damage.
  const auto before = crossings(reference, triangles);
  std::vector<char> vertex_crossed(reference.size(), 0), crossed_before(triangles.size(), 0);
  for (const auto& pair : before)
    for (int t : pair)
      for (int v : triangles[static_cast<size_t>(t)]) vertex_crossed[static_cast<size_t>(v)] = 1;
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t]) crossed_before[t] |= vertex_crossed[static_cast<size_t>(v)];
  std::vector<std::array<int, 2>> added;
  for (const auto& pair : crossings(vertices, triangles))
    if (!crossed_before[static_cast<size_t>(pair[0])] && !crossed_before[static_cast<size_t>(pair[1])]) added.push_back(pair);
  std::vector<int> involved;
  for (const auto& [a, b] : added) {
    involved.push_back(a);
    involved.push_back(b);
  }
  std::sort(involved.begin(), involved.end());
  out.self_intersecting_triangles =
      static_cast<int>(std::unique(involved.begin(), involved.end()) - involved.begin());
  out.self_intersecting_pairs = static_cast<int>(added.size());
  out.reference_self_intersecting_pairs = static_cast<int>(before.size());

  std::vector<std::string> problems;
  const double triangle_count = static_cast<double>(std::max<size_t>(triangles.size(), 1));
  if (out.strained_fraction > limits.max_strained_fraction)
    problems.push_back(format("%.3g%% of the edges strained beyond %.3gx (limit %.3g%%)",
                              100.0 * out.strained_fraction, limits.max_strain,
                              100.0 * limits.max_strained_fraction));
  if (out.longest_stretched_edge > limits.max_edge_stretch)
    problems.push_back(
        format("an edge stretched to %.3g typical edges (limit %.3g)", out.longest_stretched_edge, limits.max_edge_stretch));
  if (out.flipped_triangles > limits.max_flipped_fraction * triangle_count)
    problems.push_back(format("%.0f flipped triangles (limit %.3g%% of the triangles, %.0f)",
                              out.flipped_triangles, 100.0 * limits.max_flipped_fraction,
                              std::floor(limits.max_flipped_fraction * triangle_count)));
  if (out.self_intersecting_triangles > limits.max_self_intersecting_fraction * triangle_count)
    problems.push_back(format("%.0f triangles pass through the surface (limit %.3g%% of the triangles, %.0f)",
                              out.self_intersecting_triangles, 100.0 * limits.max_self_intersecting_fraction,
                              std::floor(limits.max_self_intersecting_fraction * triangle_count)));
  for (size_t i = 0; i < problems.size(); ++i) out.problem += (i ? "; " : "") + problems[i];
  if (!out.problem.empty()) out.problem = "implausible surface: " + out.problem;
  return out;
}

}  // namespace skinstream
