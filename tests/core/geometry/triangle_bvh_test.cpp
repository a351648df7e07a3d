#include "core/geometry/triangle_bvh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

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

TEST(TriangleBvh, RayHitsRejectABadRay) {
  const Body m = synth::make_mannequin();
  TriangleBvh bvh(m.rest, triangulate(m.faces));
  EXPECT_THROW(bvh.ray_hits(Vec3::Zero(), Vec3::Zero()), std::invalid_argument);
  EXPECT_THROW(bvh.ray_hits(Vec3(0, 0, std::nan("")), Vec3::UnitX()), std::invalid_argument);
  EXPECT_THROW(bvh.ray_hits(Vec3::Zero(), Vec3(1, std::numeric_limits<double>::infinity(), 0)),
               std::invalid_argument);
  EXPECT_TRUE(TriangleBvh({}, {}).ray_hits(Vec3::Zero(), Vec3::UnitX()).empty());
}

// Every crossing of a ray with a closed surface, brute force: the same triangles at the same
// distances, nearest first, with barycentric weights that rebuild the crossing point.
TEST(TriangleBvh, RayHitsMatchBruteForceNearestFirst) {
  const Body m = synth::make_mannequin();
  const std::vector<Triangle> tris = triangulate(m.faces);
  TriangleBvh bvh(m.rest, tris);
  synth::Random r(11);
  int crossings = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 a(r.uniform(-300, 300), r.uniform(-150, 150), r.uniform(50, 1600));
    const Vec3 dir(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1));
    const double max_distance = i % 2 ? std::numeric_limits<double>::infinity() : 400.0;
    const std::vector<RayHit> hits = bvh.ray_hits(a, 3.0 * dir, max_distance);  // scaled: distances in mm
    const Vec3 d = dir.normalized();
    std::vector<std::pair<double, int>> expected;
    for (size_t t = 0; t < tris.size(); ++t) {
      const Vec3 &v0 = m.rest[static_cast<size_t>(tris[t][0])], &v1 = m.rest[static_cast<size_t>(tris[t][1])],
                 &v2 = m.rest[static_cast<size_t>(tris[t][2])];
      const Vec3 n = (v1 - v0).cross(v2 - v0);
      const double den = n.dot(d);
      if (std::abs(den) < 1e-12) continue;
      const double s = n.dot(v0 - a) / den;
      if (s < 0.0 || s > max_distance) continue;
      const Vec3 q = a + s * d;
      if ((closest_point_on_triangle(q, v0, v1, v2) - q).norm() < 1e-7)
        expected.emplace_back(s, static_cast<int>(t));
    }
    ASSERT_EQ(hits.size(), expected.size()) << i;
    std::sort(expected.begin(), expected.end());
    for (size_t k = 0; k < hits.size(); ++k) {
      ASSERT_NEAR(hits[k].distance, expected[k].first, 1e-6) << i;
      if (k > 0) {
        ASSERT_LE(hits[k - 1].distance, hits[k].distance);
      }
      const Triangle& t = tris[static_cast<size_t>(hits[k].triangle)];
      const Vec3 p = hits[k].barycentric[0] * m.rest[static_cast<size_t>(t[0])] +
                     hits[k].barycentric[1] * m.rest[static_cast<size_t>(t[1])] +
                     hits[k].barycentric[2] * m.rest[static_cast<size_t>(t[2])];
      ASSERT_LT((p - (a + hits[k].distance * d)).norm(), 1e-6) << i;
      ASSERT_NEAR(hits[k].barycentric.sum(), 1.0, 1e-12);
      ASSERT_GE(hits[k].barycentric.minCoeff(), -1e-12);
    }
    crossings += static_cast<int>(hits.size());
  }
  EXPECT_GT(crossings, 100);  // the rays start in and around the body
}

// Rays aimed exactly at the edge two triangles share (a body's symmetry seam is full of them):
// rounding must not let one pass between them.
TEST(TriangleBvh, RayHitsDoNotSlipThroughASharedEdge) {
  synth::Random r(3);
  int slipped_without_slack = 0;
  for (int i = 0; i < 2000; ++i) {
    // Two triangles folded along the edge a-b, and a ray through a point of that edge.
    const Vec3 a(r.uniform(-50, 50), r.uniform(-50, 50), r.uniform(-50, 50));
    const Vec3 b(r.uniform(-50, 50), r.uniform(-50, 50), r.uniform(-50, 50));
    const Vec3 c(r.uniform(-50, 50), r.uniform(-50, 50), r.uniform(-50, 50));
    const Vec3 d = a + b - c + Vec3(r.uniform(-9, 9), r.uniform(-9, 9), r.uniform(-9, 9));
    const TriangleBvh bvh({a, b, c, d}, {{0, 1, 2}, {1, 0, 3}});
    const Vec3 on_edge = a + r.uniform(0.05, 0.95) * (b - a);
    const Vec3 normal = (b - a).cross(c - a).normalized();
    const Vec3 origin = on_edge - 40.0 * normal + Vec3(r.uniform(-5, 5), r.uniform(-5, 5), r.uniform(-5, 5));
    const std::vector<RayHit> hits = bvh.ray_hits(origin, on_edge - origin);
    ASSERT_FALSE(hits.empty()) << i;
    EXPECT_NEAR(hits[0].distance, (on_edge - origin).norm(), 1e-6);
    for (const RayHit& h : hits) EXPECT_GE(h.barycentric.minCoeff(), 0.0);
    slipped_without_slack += !bvh.segment_blocked(origin, on_edge + (on_edge - origin), 0.0);
  }
  // The same rays as segments (exact triangle bounds) do slip now and then: the case is real.
  EXPECT_GT(slipped_without_slack, 0);
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

TEST(TriangleBvh, SelfIntersectionsMatchBruteForce) {
  // The mannequin, then the same with its left arm swung through the chest: the BVH query
  // finds exactly the crossing pairs that testing every pair finds.
  const Body m = synth::make_mannequin();
  const std::vector<Triangle> tris = triangulate(m.faces);
  auto brute = [&](const std::vector<Vec3>& p) {
    std::vector<std::array<int, 2>> pairs;
    for (size_t i = 0; i < tris.size(); ++i)
      for (size_t j = i + 1; j < tris.size(); ++j) {
        const Triangle &t = tris[i], &u = tris[j];
        bool shared = false;
        for (int a : t)
          for (int b : u) shared = shared || a == b;
        Eigen::AlignedBox3d bt, bu;  // apart boxes cannot cross (cheap, and not the BVH's code)
        for (int k = 0; k < 3; ++k) {
          bt.extend(p[static_cast<size_t>(t[static_cast<size_t>(k)])]);
          bu.extend(p[static_cast<size_t>(u[static_cast<size_t>(k)])]);
        }
        if (!shared && bt.intersects(bu) && triangles_cross(p[static_cast<size_t>(t[0])], p[static_cast<size_t>(t[1])],
                                       p[static_cast<size_t>(t[2])], p[static_cast<size_t>(u[0])],
                                       p[static_cast<size_t>(u[1])], p[static_cast<size_t>(u[2])]))
          pairs.push_back({static_cast<int>(i), static_cast<int>(j)});
      }
    return pairs;
  };
  TriangleBvh bvh(m.rest, tris);
  EXPECT_EQ(bvh.self_intersections(), brute(m.rest));
  // Every vertex left of the body's middle and above the hips moves 40% of the body's width
  // to the right: the left side passes through the right.
  double lo = 1e30, hi = -1e30, top = -1e30;
  for (const Vec3& p : m.rest) {
    lo = std::min(lo, p.x());
    hi = std::max(hi, p.x());
    top = std::max(top, p.z());
  }
  std::vector<Vec3> moved = m.rest;
  for (Vec3& p : moved)
    if (p.x() < 0.5 * (lo + hi) && p.z() > 0.5 * top) p.x() += 0.4 * (hi - lo);
  bvh.refit(moved);
  const auto pairs = bvh.self_intersections();
  EXPECT_GT(pairs.size(), 10u);
  EXPECT_EQ(pairs, brute(moved));
  TriangleBvh empty({}, {});
  EXPECT_TRUE(empty.self_intersections().empty());
}

}  // namespace
}  // namespace skinstream
