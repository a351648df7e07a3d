#pragma once
// Shared fixtures for the deform tests: random rigid motions, point sets and non-rigid fields.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"
#include "core/deform/deformation_model.h"
#include "core/subject_model.h"

namespace skinstream::deform_test {

inline RigidTransform random_motion(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  RigidTransform t;
  t.rotation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  t.translation = Vec3(g(rng), g(rng), g(rng)) * 500.0;
  return t;
}

inline std::vector<Vec3> random_points(std::mt19937_64& rng, int count, const Vec3& half_extent,
                                       const Vec3& centre = Vec3(300, -200, 900)) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> points(count);
  for (Vec3& p : points) p = centre + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(half_extent);
  return points;
}

// A smooth non-rigid bulge and twist (a few mm on a ~100 mm part), then a rigid motion.
inline std::vector<Vec3> deform_non_rigidly(const std::vector<Vec3>& points, const RigidTransform& motion) {
  std::vector<Vec3> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const Vec3 bulge(3.0 * std::sin(p.y() / 40.0), 2.0 * std::cos(p.z() / 30.0), 4.0 * std::sin(p.x() / 50.0));
    out[i] = motion.apply(p + bulge);
  }
  return out;
}

inline std::vector<Vec3> move_rigidly(const std::vector<Vec3>& points, const RigidTransform& motion) {
  std::vector<Vec3> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) out[i] = motion.apply(points[i]);
  return out;
}

// A wavy sheet, 10 mm between grid points: a side x side vertex grid in triangles that share
// their vertices (valence up to 6, and a boundary), markers on every third grid point (100 for
// the default side of 31), two parts that overlap in the middle third of the sheet's x extent,
// where the vertices are blended between them.
struct WavySheet {
  SubjectModel subject;
  DeformationModel model;

  explicit WavySheet(int side = 31) {
    const int kSide = side;
    const double third = 10.0 * (kSide - 1) / 3.0;
    auto at = [](int i, int j) { return Vec3(10.0 * i, 10.0 * j, 15.0 * std::sin(i / 5.0) * std::cos(j / 7.0)); };
    model.part_names = {"left", "right"};
    for (int i = 0; i < kSide; i += 3)
      for (int j = 0; j < kSide; j += 3) {
        subject.marker_names.push_back("m" + std::to_string(subject.marker_names.size()));
        subject.reference_positions.push_back(at(i, j));
      }
    for (int part = 0; part < 2; ++part) {
      for (int m = 0; m < static_cast<int>(subject.reference_positions.size()); ++m) {
        const double x = subject.reference_positions[m].x();
        if (part == 0 ? x <= 2.0 * third : x >= third) model.part_members.push_back({m, 1.0});
      }
      model.part_member_offsets.push_back(static_cast<int>(model.part_members.size()));
    }
    for (int i = 0; i < kSide; ++i)
      for (int j = 0; j < kSide; ++j) {
        model.reference_vertices.push_back(at(i, j));
        const double x = 10.0 * i, right = std::clamp((x - third) / third, 0.0, 1.0);
        if (right < 1.0) model.vertex_influences.push_back({0, 1.0 - right});
        if (right > 0.0) model.vertex_influences.push_back({1, right});
        model.vertex_influence_offsets.push_back(static_cast<int>(model.vertex_influences.size()));
      }
    for (int i = 0; i + 1 < kSide; ++i)
      for (int j = 0; j + 1 < kSide; ++j) {
        const int a = i * kSide + j, b = a + kSide, c = b + 1, d = a + 1;
        model.faces.push_back({a, b, c});
        model.faces.push_back({a, c, d});
      }
  }
};

}  // namespace skinstream::deform_test
