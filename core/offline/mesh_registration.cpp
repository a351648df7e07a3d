#include "core/offline/mesh_registration.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/absolute_orientation.h"
#include "core/geometry/triangle_bvh.h"
#include "core/geometry/triangle_mesh.h"
#include "core/deform/mesh_edges.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

using Triangles = std::span<const std::array<int, 3>>;

constexpr Precondition require_registration{"mesh registration"};

void check_points(std::span<const Vec3> points, const char* what) {
  for (size_t i = 0; i < points.size(); ++i)
    require_registration(points[i].allFinite(), std::string(what) + " " + std::to_string(i) + " is not finite");
}

void check_mesh(std::span<const Vec3> vertices, Triangles triangles) {
  require_registration(!vertices.empty(), "the mesh has no vertices");
  require_registration(!triangles.empty(), "the mesh has no triangles");
  check_points(vertices, "vertex");
  const int n = static_cast<int>(vertices.size());
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t])
      require_registration(v >= 0 && v < n, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " of " +
                                   std::to_string(n));
}

std::vector<Triangle> to_triangles(Triangles triangles) { return {triangles.begin(), triangles.end()}; }

// Centre and RMS radius of the mesh: the internal coordinates are (p - centre) / scale.
struct Normalisation {
  Vec3 centre = Vec3::Zero();
  double scale = 1.0;
  Vec3 to_unit(const Vec3& p) const { return (p - centre) / scale; }
  Vec3 to_mm(const Vec3& p) const { return p * scale + centre; }
};

Normalisation normalisation_of(std::span<const Vec3> vertices) {
  Normalisation n;
  for (const Vec3& v : vertices) n.centre += v;
  n.centre /= static_cast<double>(vertices.size());
  double s = 0.0;
  for (const Vec3& v : vertices) s += (v - n.centre).squaredNorm();
  n.scale = std::sqrt(s / vertices.size());
  if (!(n.scale > 0.0)) n.scale = 1.0;  // a single point or coincident vertices
  return n;
}

// The normal equations H X = B of the current linearised objective (X: 4n x 3).
class NormalEquations {
 public:
  explicit NormalEquations(int vertex_count) : b_(Eigen::MatrixX3d::Zero(4 * vertex_count, 3)) {}

  // w * |sum_k coef_k * [v_k^T 1] X_k - target|^2
  template <int N>
  void add_point_row(double w, const std::array<int, N>& vertex, const std::array<double, N>& coef,
                     const std::vector<Vec3>& unit_vertices, const Vec3& target) {
    std::array<int, 4 * N> index;
    std::array<double, 4 * N> a;
    for (int k = 0; k < N; ++k) {
      const Vec3& v = unit_vertices[vertex[k]];
      for (int c = 0; c < 4; ++c) {
        index[4 * k + c] = 4 * vertex[k] + c;
        a[4 * k + c] = coef[k] * (c < 3 ? v[c] : 1.0);
      }
    }
    for (int r = 0; r < 4 * N; ++r) {
      for (int c = 0; c < 4 * N; ++c) triplets_.emplace_back(index[r], index[c], w * a[r] * a[c]);
      b_.row(index[r]) += w * a[r] * target.transpose();
    }
  }

  void add_smoothness(double w, int i, int j) {
    for (int c = 0; c < 4; ++c) {
      triplets_.emplace_back(4 * i + c, 4 * i + c, w);
      triplets_.emplace_back(4 * j + c, 4 * j + c, w);
      triplets_.emplace_back(4 * i + c, 4 * j + c, -w);
      triplets_.emplace_back(4 * j + c, 4 * i + c, -w);
    }
  }

  void add_damping(double w, const Eigen::MatrixX3d& previous) {
    for (int r = 0; r < previous.rows(); ++r) triplets_.emplace_back(r, r, w);
    b_ += w * previous;
  }

  Eigen::MatrixX3d solve() {
    Eigen::SparseMatrix<double> h(b_.rows(), b_.rows());
    h.setFromTriplets(triplets_.begin(), triplets_.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(h);
    if (solver.info() != Eigen::Success) throw std::runtime_error("mesh registration: the normal equations are singular");
    Eigen::MatrixX3d x = solver.solve(b_);
    if (solver.info() != Eigen::Success || !x.allFinite())
      throw std::runtime_error("mesh registration: the linear solve failed");
    return x;
  }

 private:
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::MatrixX3d b_;
};

std::vector<Vec3> apply_transforms(const std::vector<Vec3>& unit_vertices, const Eigen::MatrixX3d& x) {
  std::vector<Vec3> out(unit_vertices.size());
  for (size_t j = 0; j < unit_vertices.size(); ++j) {
    const Eigen::RowVector4d h(unit_vertices[j].x(), unit_vertices[j].y(), unit_vertices[j].z(), 1.0);
    out[j] = (h * x.middleRows<4>(4 * static_cast<Eigen::Index>(j))).transpose();
  }
  return out;
}

SurfaceDistance distance_stats(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles,
                               std::span<const Vec3> markers, double offset, double to_mm) {
  const TriangleBvh bvh(points, triangles);
  SurfaceDistance d;
  if (markers.empty()) return d;
  double sum = 0.0, sum2 = 0.0;
  for (const Vec3& m : markers) {
    const double e = std::abs(bvh.closest(m) - offset) * to_mm;
    sum += e;
    sum2 += e * e;
    d.max = std::max(d.max, e);
  }
  d.mean = sum / markers.size();
  d.rms = std::sqrt(sum2 / markers.size());
  return d;
}

std::pair<double, double> landmark_residual(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles,
                                            std::span<const Vec3> markers, std::span<const RegistrationLandmark> landmarks,
                                            double offset, double to_mm) {
  const std::vector<Vec3> normals = vertex_normals(points, triangles);
  double sum2 = 0.0, max = 0.0;
  for (const RegistrationLandmark& l : landmarks) {
    Vec3 point = points[l.vertex], normal = normals[l.vertex];
    if (l.triangle >= 0) {
      const Triangle& t = triangles[static_cast<size_t>(l.triangle)];
      point = l.barycentric[0] * points[t[0]] + l.barycentric[1] * points[t[1]] + l.barycentric[2] * points[t[2]];
      normal = triangle_normal(points[t[0]], points[t[1]], points[t[2]]);
    }
    const double e = (point - (markers[l.marker] - offset * normal)).norm() * to_mm;
    sum2 += e * e;
    max = std::max(max, e);
  }
  return {std::sqrt(sum2 / landmarks.size()), max};
}

}  // namespace

SurfaceDistance marker_surface_distance(std::span<const Vec3> vertices, Triangles triangles, std::span<const Vec3> markers,
                                        double marker_offset_mm) {
  check_mesh(vertices, triangles);
  check_points(markers, "marker");
  return distance_stats({vertices.begin(), vertices.end()}, to_triangles(triangles), markers, marker_offset_mm, 1.0);
}

std::vector<Vec3> register_mesh(std::span<const Vec3> vertices, Triangles triangles, std::span<const Vec3> markers,
                                std::span<const RegistrationLandmark> landmarks, const RegistrationOptions& options,
                                RegistrationReport* out_report) {
  check_mesh(vertices, triangles);
  require_registration(!markers.empty(), "no markers");
  check_points(markers, "marker");
  require_registration(!landmarks.empty(), "no landmarks (give marker/vertex pairs or use guess_landmarks)");
  const int n = static_cast<int>(vertices.size());
  const int m = static_cast<int>(markers.size());
  for (size_t i = 0; i < landmarks.size(); ++i) {
    require_registration(landmarks[i].marker >= 0 && landmarks[i].marker < m,
            "landmark " + std::to_string(i) + " names marker " + std::to_string(landmarks[i].marker) + " of " + std::to_string(m));
    if (landmarks[i].triangle >= 0) {
      require_registration(landmarks[i].triangle < static_cast<int>(triangles.size()),
              "landmark " + std::to_string(i) + " names triangle " + std::to_string(landmarks[i].triangle) + " of " +
                  std::to_string(triangles.size()));
      require_registration(landmarks[i].barycentric.allFinite(), "landmark " + std::to_string(i) + " has non-finite barycentric coordinates");
    } else {
      require_registration(landmarks[i].vertex >= 0 && landmarks[i].vertex < n,
              "landmark " + std::to_string(i) + " names vertex " + std::to_string(landmarks[i].vertex) + " of " + std::to_string(n));
    }
  }
  for (double w : {options.data_weight, options.smoothness_weight, options.landmark_weight, options.damping_weight,
                   options.marker_offset_mm, options.tolerance_mm})
    require_registration(std::isfinite(w) && w >= 0.0, "weights, offset and tolerance must be finite and >= 0");
  require_registration(options.damping_weight > 0.0 || options.smoothness_weight > 0.0, "smoothness and damping are both 0");
  require_registration(options.max_iterations >= 0, "max_iterations must be >= 0");

  const Normalisation norm = normalisation_of(vertices);
  std::vector<Vec3> unit_vertices(vertices.size());
  for (int j = 0; j < n; ++j) unit_vertices[j] = norm.to_unit(vertices[j]);
  std::vector<Vec3> unit_markers(markers.size());
  for (int i = 0; i < m; ++i) unit_markers[i] = norm.to_unit(markers[i]);
  const double offset = options.marker_offset_mm / norm.scale;
  const std::vector<Triangle> tris = to_triangles(triangles);
  const std::vector<std::pair<int, int>> edges = unique_edges(triangles);

  Eigen::MatrixX3d x = Eigen::MatrixX3d::Zero(4 * n, 3);
  for (int j = 0; j < n; ++j) x.block<3, 3>(4 * j, 0).setIdentity();

  RegistrationReport report;
  report.before = distance_stats(unit_vertices, tris, unit_markers, offset, norm.scale);
  report.landmark_rms_before_mm = landmark_residual(unit_vertices, tris, unit_markers, landmarks, offset, norm.scale).first;

  // One linear solve with the correspondences of the current deformed mesh.
  auto iterate = [&](double data_weight) {
    const std::vector<Vec3> current = apply_transforms(unit_vertices, x);
    const std::vector<Vec3> normals = vertex_normals(current, tris);
    NormalEquations eq(n);
    // Each term is a mean (per edge, per vertex, per landmark, per marker), so that equal
    // weights mean equal say whatever the mesh resolution and the marker count.
    const double smoothness = options.smoothness_weight / std::max<size_t>(1, edges.size());
    const double damping = options.damping_weight / n;
    const double landmark = options.landmark_weight / landmarks.size();
    const double data = data_weight / m;
    for (const auto& [i, j] : edges) eq.add_smoothness(smoothness, i, j);
    eq.add_damping(damping, x);
    for (const RegistrationLandmark& l : landmarks) {
      if (l.triangle >= 0) {
        const Triangle& t = tris[static_cast<size_t>(l.triangle)];
        const Vec3 normal = triangle_normal(current[t[0]], current[t[1]], current[t[2]]);
        eq.add_point_row<3>(landmark, t, {l.barycentric[0], l.barycentric[1], l.barycentric[2]}, unit_vertices,
                            unit_markers[l.marker] - offset * normal);
      } else {
        eq.add_point_row<1>(landmark, {l.vertex}, {1.0}, unit_vertices, unit_markers[l.marker] - offset * normals[l.vertex]);
      }
    }
    if (data_weight > 0.0) {
      const TriangleBvh bvh(current, tris);
      for (const Vec3& marker : unit_markers) {
        int t = -1;
        bvh.closest(marker, &t);
        const Triangle& tri = tris[t];
        Vec3 bary;
        closest_point_on_triangle(marker, current[tri[0]], current[tri[1]], current[tri[2]], &bary);
        const Vec3 normal = triangle_normal(current[tri[0]], current[tri[1]], current[tri[2]]);
        eq.add_point_row<3>(data, tri, {bary[0], bary[1], bary[2]}, unit_vertices, marker - offset * normal);
      }
    }
    x = eq.solve();
    ++report.iterations;
  };

  if (options.global_phase) iterate(0.0);
  std::vector<Vec3> current = apply_transforms(unit_vertices, x);
  report.after_global = distance_stats(current, tris, unit_markers, offset, norm.scale);
  double previous_mean = report.after_global.mean;
  report.after = report.after_global;
  for (int it = 0; it < options.max_iterations; ++it) {
    iterate(options.data_weight);
    current = apply_transforms(unit_vertices, x);
    report.after = distance_stats(current, tris, unit_markers, offset, norm.scale);
    if (previous_mean - report.after.mean < options.tolerance_mm) break;
    previous_mean = report.after.mean;
  }
  const auto [landmark_rms, landmark_max] = landmark_residual(current, tris, unit_markers, landmarks, offset, norm.scale);
  report.landmark_rms_after_mm = landmark_rms;
  report.landmark_max_after_mm = landmark_max;

  std::vector<Vec3> out(current.size());
  for (size_t j = 0; j < current.size(); ++j) out[j] = norm.to_mm(current[j]);
  if (out_report) *out_report = report;
  return out;
}

std::vector<RegistrationLandmark> guess_landmarks(std::span<const Vec3> vertices, std::span<const Vec3> markers,
                                                  const LandmarkGuessOptions& options) {
  require_registration(!vertices.empty(), "no vertices to guess landmarks on");
  require_registration(!markers.empty(), "no markers to guess landmarks for");
  check_points(vertices, "vertex");
  check_points(markers, "marker");
  const int m = static_cast<int>(markers.size());

  // Similarity s R v + t; starts by matching centroids and RMS radii.
  const Normalisation mesh = normalisation_of(vertices), marker_set = normalisation_of(markers);
  double s = marker_set.scale / mesh.scale;
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Vec3 t = marker_set.centre - s * mesh.centre;

  std::vector<int> nearest(markers.size(), 0);
  std::vector<double> nearest_distance(markers.size(), 0.0);
  auto match = [&] {
    for (int i = 0; i < m; ++i) {
      // Brute force is fine: a few hundred markers against tens of thousands of vertices.
      double best = std::numeric_limits<double>::infinity();
      const Vec3 target = r.transpose() * ((markers[i] - t) / s);  // marker in mesh coordinates
      for (size_t j = 0; j < vertices.size(); ++j) {
        const double d = (vertices[j] - target).squaredNorm();
        if (d < best) {
          best = d;
          nearest[i] = static_cast<int>(j);
        }
      }
      nearest_distance[i] = std::sqrt(best) * s;
    }
  };
  std::vector<int> previous;
  for (int it = 0; it < options.alignment_iterations; ++it) {
    match();
    if (nearest == previous) break;  // converged: the same pairs give the same similarity
    previous = nearest;
    std::vector<Vec3> source(markers.size());
    for (int i = 0; i < m; ++i) source[i] = vertices[nearest[i]];
    RigidTransform rigid;
    fit_rigid(source, markers, rigid);
    Vec3 source_mean = Vec3::Zero(), target_mean = Vec3::Zero();
    for (int i = 0; i < m; ++i) {
      source_mean += source[i];
      target_mean += markers[i];
    }
    source_mean /= m;
    target_mean /= m;
    double num = 0.0, den = 0.0;
    for (int i = 0; i < m; ++i) {
      const Vec3 a = rigid.rotation * (source[i] - source_mean);
      num += a.dot(markers[i] - target_mean);
      den += a.squaredNorm();
    }
    if (!(den > 0.0) || !(num > 0.0)) break;  // degenerate: keep the previous similarity
    r = rigid.rotation;
    s = num / den;
    t = target_mean - s * r * source_mean;
  }
  match();
  std::vector<RegistrationLandmark> out;
  for (int i = 0; i < m; ++i)
    if (nearest_distance[i] <= options.max_distance_mm) out.push_back({i, nearest[i]});
  return out;
}

}  // namespace skinstream
