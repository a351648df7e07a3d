#include "core/fitting/surface_checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <stdexcept>

#include "core/geometry/triangle_bvh.h"
#include "core/deform/surface_strain.h"

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
  const EdgeStrain strain = measure_edge_strain(reference, vertices, triangles, limits.max_strain);
  out.scale = strain.scale;
  out.strained_fraction = strain.strained_fraction;
  out.max_strain = strain.max_strain;
  out.max_stretch = strain.max_stretch;
  out.longest_stretched_edge = strain.longest_stretched_edge;
  out.strained_edges = strain.strained_edges;
  out.edges = strain.edges;
  out.flipped_triangles = count_flipped_triangles(reference, vertices, triangles);

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
