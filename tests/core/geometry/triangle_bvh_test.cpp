#include "core/geometry/triangle_bvh.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/synth/mannequin.h"
#include "core/synth/random.h"

namespace skinstream {
namespace {

// Brute force: does any triangle cross the segment (beyond skip at both ends)?
bool brute_blocked(const std::vector<Vec3>& p, const std::vector<Triangle>& tris, const Vec3& a,
                   const Vec3& b, double skip) {
  const Vec3 d = (b - a).normalized();
  const double len = (b - a).norm();
  for (const Triangle& t : tris) {
    const Vec3 &v0 = p[static_cast<size_t>(t[0])], &v1 = p[static_cast<size_t>(t[1])],
               &v2 = p[static_cast<size_t>(t[2])];
    const Vec3 n = (v1 - v0).cross(v2 - v0);
    const double den = n.dot(d);
    if (std::abs(den) < 1e-12) continue;
    const double s = n.dot(v0 - a) / den;
    if (s <= skip || s >= len - skip) continue;
    const Vec3 q = a + s * d;
    const Vec3 c = closest_point_on_triangle(q, v0, v1, v2);
    if ((c - q).norm() < 1e-7) return true;
  }
  return false;
}

TEST(TriangleBvh, RejectsBadTriangles) {
  EXPECT_THROW(TriangleBvh({Vec3::Zero()}, {{0, 1, 2}}), std::invalid_argument);
  TriangleBvh empty({}, {});
  EXPECT_FALSE(empty.segment_blocked(Vec3::Zero(), Vec3::UnitX()));
  EXPECT_EQ(empty.closest(Vec3::Zero()), std::numeric_limits<double>::infinity());
}

TEST(TriangleBvh, SegmentAndClosestQueriesMatchBruteForceAfterRefit) {
  const Body m = synth::make_mannequin();
  const std::vector<Triangle> tris = triangulate(m.faces);
  TriangleBvh bvh(m.rest, tris);
  std::vector<Vec3> moved = m.rest;
  for (Vec3& p : moved)
    p = Vec3(p.x() * 1.1 + 0.05 * p.z(), p.y() - 0.1 * p.x(), p.z());  // deform, then refit
  for (const std::vector<Vec3>* pts : std::vector<const std::vector<Vec3>*>{&m.rest, &moved}) {
    bvh.refit(*pts);
    synth::Random r(5);
    int blocked = 0;
    for (int i = 0; i < 300; ++i) {
      const Vec3 a(r.uniform(-400, 400), r.uniform(-300, 300), r.uniform(0, 1800));
      const Vec3 b(r.uniform(-3000, 3000), r.uniform(-3000, 3000), r.uniform(0, 2500));
      const bool fast = bvh.segment_blocked(a, b, 1.0);
      ASSERT_EQ(fast, brute_blocked(*pts, tris, a, b, 1.0)) << i;
      blocked += fast;
      int t = -1;
      Vec3 q;
      const double d = bvh.closest(a, &t, &q);
      double best = std::numeric_limits<double>::infinity();
      for (const Triangle& tri : tris)
        best = std::min(best, (closest_point_on_triangle(a, (*pts)[static_cast<size_t>(tri[0])],
                                                         (*pts)[static_cast<size_t>(tri[1])],
                                                         (*pts)[static_cast<size_t>(tri[2])]) -
                               a)
                                  .norm());
      ASSERT_NEAR(d, best, 1e-9);
      ASSERT_NEAR((q - a).norm(), d, 1e-9);
      ASSERT_GE(t, 0);
    }
    EXPECT_GT(blocked, 30);   // the sample hits the body often
    EXPECT_LT(blocked, 290);  // and misses it often
  }
}

}  // namespace
}  // namespace skinstream
