#include "core/geometry/triangle_mesh.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace skinstream
