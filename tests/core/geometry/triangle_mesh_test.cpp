#include "core/geometry/triangle_mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace skinstream {
namespace {

TEST(TriangleMesh, ClosestPointOnTriangleAndVolume) {
  const Vec3 a(0, 0, 0), b(10, 0, 0), c(0, 10, 0);
  Vec3 bary;
  EXPECT_TRUE(closest_point_on_triangle(Vec3(2, 3, 5), a, b, c, &bary).isApprox(Vec3(2, 3, 0)));
  EXPECT_NEAR(bary.sum(), 1.0, 1e-12);
  EXPECT_TRUE(closest_point_on_triangle(Vec3(-5, -5, 1), a, b, c).isApprox(a));
  EXPECT_TRUE(closest_point_on_triangle(Vec3(10, 10, 0), a, b, c).isApprox(Vec3(5, 5, 0)));
  // A unit cube with outward faces.
  const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const std::vector<Face> quads = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                   {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  EXPECT_NEAR(signed_volume(p, triangulate(quads)), 1.0, 1e-12);
  const auto n = vertex_normals(p, triangulate(quads));
  EXPECT_GT(n[6].dot(Vec3(1, 1, 1)), 0.9 * std::sqrt(3.0));
}

TEST(TriangleMesh, TrianglesCrossOnlyWhenOnePassesThroughTheOther) {
  const Vec3 a0(0, 0, 0), a1(10, 0, 0), a2(0, 10, 0);
  // A triangle piercing the first one, in either vertex order and either role.
  const Vec3 b0(2, 2, -5), b1(2, 2, 5), b2(8, 8, 5);
  EXPECT_TRUE(triangles_cross(a0, a1, a2, b0, b1, b2));
  EXPECT_TRUE(triangles_cross(b0, b1, b2, a0, a1, a2));
  EXPECT_TRUE(triangles_cross(a0, a2, a1, b2, b1, b0));
  // An edge of each through the other's interior, no vertex inside (two interlocked rings).
  EXPECT_TRUE(triangles_cross(a0, a1, a2, Vec3(3, 3, -5), Vec3(3, 3, 5), Vec3(3, -20, 0)));
  // Above, beside, past the hypotenuse: apart.
  EXPECT_FALSE(triangles_cross(a0, a1, a2, Vec3(2, 2, 1), Vec3(2, 2, 5), Vec3(8, 8, 5)));
  EXPECT_FALSE(triangles_cross(a0, a1, a2, Vec3(6, 6, -5), Vec3(6, 6, 5), Vec3(9, 9, 5)));
  EXPECT_FALSE(triangles_cross(a0, a1, a2, Vec3(20, 0, -5), Vec3(20, 0, 5), Vec3(25, 5, 0)));
  // Touching (a vertex on the other's face, a shared edge) and coplanar overlap do not cross.
  EXPECT_FALSE(triangles_cross(a0, a1, a2, Vec3(2, 2, 0), Vec3(2, 2, 5), Vec3(8, 8, 5)));
  EXPECT_FALSE(triangles_cross(a0, a1, a2, a0, a1, Vec3(5, -5, 3)));
  EXPECT_FALSE(triangles_cross(a0, a1, a2, Vec3(1, 1, 0), Vec3(11, 1, 0), Vec3(1, 11, 0)));
  // Pairs of triangles in one random plane far from the origin, apart or overlapping: rounding
  // puts their corners on either side of each other's plane, which must not read as a crossing.
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto point = [&] { return Vec3(uniform(random), uniform(random), uniform(random)); };
  int crossed = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 origin = 2000.0 * point(), u = point().normalized(), w = u.cross(point()).normalized();
    const auto in_plane = [&] {
      return Vec3(origin + 30.0 * uniform(random) * u + 30.0 * uniform(random) * w);
    };
    crossed += triangles_cross(in_plane(), in_plane(), in_plane(), in_plane(), in_plane(), in_plane());
  }
  EXPECT_EQ(crossed, 0);
}

}  // namespace
}  // namespace skinstream
