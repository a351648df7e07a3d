#include "core/deform/surface_strain.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/deform/mesh_edges.h"

namespace skinstream {

namespace {

// Unit normal of a counter-clockwise triangle; zero when it has no area.
Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0.0 ? Vec3(n / length) : Vec3::Zero();
}

}  // namespace

EdgeStrain measure_edge_strain(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                               std::span<const std::array<int, 3>> triangles, double max_strain) {
  EdgeStrain out;
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
  if (ratios.empty()) return out;
  std::vector<double> sorted = ratios;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  out.scale = sorted[sorted.size() / 2];
  if (!(out.scale > 0.0)) {  // more than half the edges collapsed: everything is strained
    out.strained_edges = out.edges;
    out.strained_fraction = 1.0;
    out.max_strain = out.max_stretch = out.longest_stretched_edge = std::numeric_limits<double>::infinity();
    return out;
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
    out.strained_edges += strain > max_strain;
  }
  out.strained_fraction = static_cast<double>(out.strained_edges) / static_cast<double>(out.edges);
  return out;
}

// Flips: each triangle against the rotation of its neighbourhood (the vertices of every
// triangle that shares a vertex with it), fitted by least squares (Kabsch). A pose bends the
// surface smoothly, so a neighbourhood turns with the triangle; a triangle turned inside out
// against its neighbours is a fold.
int count_flipped_triangles(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                            std::span<const std::array<int, 3>> triangles) {
  const size_t n = reference.size();
  std::vector<int> offsets(n + 1, 0), incident;
  for (const std::array<int, 3>& t : triangles)
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
    const std::array<int, 3>& tri = triangles[t];
    const Vec3 n_ref =
        unit_normal(reference[static_cast<size_t>(tri[0])], reference[static_cast<size_t>(tri[1])],
                        reference[static_cast<size_t>(tri[2])]);
    if (n_ref.isZero()) continue;  // no orientation to keep
    const Vec3 n_new =
        unit_normal(vertices[static_cast<size_t>(tri[0])], vertices[static_cast<size_t>(tri[1])],
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

}  // namespace skinstream
