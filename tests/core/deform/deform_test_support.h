#pragma once
// Shared fixtures for the deform tests: random rigid motions, point sets and non-rigid fields.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"

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

}  // namespace skinstream::deform_test
