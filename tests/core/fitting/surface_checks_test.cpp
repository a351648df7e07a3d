#include "core/fitting/surface_checks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/deform/mesh_edges.h"
#include "tests/core/fitting/fitting_test_support.h"

namespace skinstream {
namespace {

using test::template_body;

void print(const char* name, const SurfaceCheck& c) {
  std::printf(
      "surface check, %s: scale %.3f, %.3f%% of %d edges strained > 1.5x, worst strain %.2fx, stretch %.2fx; "
      "%d "
      "flipped, %d crossing triangles (%d pairs)%s%s\n",
      name, c.scale, 100.0 * c.strained_fraction, c.edges, c.max_strain, c.max_stretch, c.flipped_triangles,
      c.self_intersecting_triangles, c.self_intersecting_pairs, c.ok() ? "" : ": ", c.problem.c_str());
}

TEST(SurfaceCheck, RejectsBadInput) {
  const auto& t = template_body();
  const std::vector<Vec3>& rest = t.body.rest;
  const std::vector<Vec3> shorter(rest.begin(), rest.end() - 1);
  EXPECT_THROW(check_surface(rest, shorter, t.triangles), std::invalid_argument);
  std::vector<Triangle> out_of_range = t.triangles;
  out_of_range[3][1] = -1;
  EXPECT_THROW(check_surface(rest, rest, out_of_range), std::invalid_argument);
  std::vector<Vec3> not_finite = rest;
  not_finite[10].x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(check_surface(not_finite, rest, t.triangles), std::invalid_argument);
  SurfaceCheckLimits bad;
  bad.max_strain = 0.9;
  EXPECT_THROW(check_surface(rest, rest, t.triangles, bad), std::invalid_argument);
  bad = {};
  bad.max_flipped_fraction = -1.0;
  EXPECT_THROW(check_surface(rest, rest, t.triangles, bad), std::invalid_argument);
  // A deformed vertex that is not finite is a finding, not an input error.
  const SurfaceCheck c = check_surface(rest, not_finite, t.triangles);
  EXPECT_EQ(c.problem, "1 of 13380 vertices are not finite");
}

TEST(SurfaceCheck, TemplateAgainstItselfRigidMotionAndScale) {
  const auto& t = template_body();
  const std::vector<Vec3>& rest = t.body.rest;
  const auto start = std::chrono::steady_clock::now();
  const SurfaceCheck same = check_surface(rest, rest, t.triangles, SurfaceCheckLimits::at_rest());
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(same.ok()) << same.problem;
  EXPECT_EQ(same.scale, 1.0);
  EXPECT_EQ(same.strained_edges, 0);
  EXPECT_EQ(same.max_strain, 1.0);
  EXPECT_EQ(same.flipped_triangles, 0);
  EXPECT_EQ(same.self_intersecting_triangles, 0);
  EXPECT_EQ(same.reference_self_intersecting_pairs, 0);
  EXPECT_EQ(same.edges, 40134);
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)  // several times slower there
  EXPECT_LT(ms, 1000.0);  // 26,756 triangles, two BVH self-intersection queries included
#endif
  std::printf("surface check of the template (%zu triangles): %.0f ms\n", t.triangles.size(), ms);

  const Eigen::Matrix3d r = Eigen::AngleAxisd(2.0, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vec3> moved;
  for (const Vec3& p : rest) moved.push_back(0.37 * (r * p) + Vec3(100, -2000, 30));
  const SurfaceCheck rigid = check_surface(rest, moved, t.triangles, SurfaceCheckLimits::at_rest());
  EXPECT_TRUE(rigid.ok()) << rigid.problem;
  EXPECT_NEAR(rigid.scale, 0.37, 1e-12);
  EXPECT_NEAR(rigid.max_strain, 1.0, 1e-9);
  EXPECT_EQ(rigid.flipped_triangles, 0);
  EXPECT_EQ(rigid.self_intersecting_triangles, 0);
}

TEST(SurfaceCheck, SkinnedPoseIsWithinTheLimits) {
  // Arms raised 120 degrees from hanging, both knees bent 90: linear blend skinning stretches the
  // armpits, collapses the creases and presses the calves into the thighs, within the limits.
  const auto& t = template_body();
  const std::vector<Vec3> posed = test::posed_template([](PoseBuilder& p) {
    for (Side s : {kLeft, kRight}) {
      p.shoulder(s, 0.0, 120.0);
      p.knee(s, 90.0);
    }
  });
  const SurfaceCheck c = check_surface(t.body.rest, posed, t.triangles);
  print("arms raised 120, knees 90 (skinned)", c);
  EXPECT_TRUE(c.ok()) << c.problem;
  EXPECT_NEAR(c.scale, 1.0, 0.01);
  EXPECT_GT(c.strained_edges, 0);  // the pose does strain some edges
  EXPECT_LT(c.strained_fraction, 0.01);
  // At rest the same mesh would be refused: it folds and crosses itself.
  EXPECT_FALSE(check_surface(t.body.rest, posed, t.triangles, SurfaceCheckLimits::at_rest()).ok());

  const std::vector<Vec3> raised = test::posed_template([](PoseBuilder& p) {
    for (Side s : {kLeft, kRight}) {
      p.shoulder(s, 0.0, 150.0);
      p.knee(s, 60.0);
      p.hip(s, 90.0, 30.0);
    }
  });
  const SurfaceCheck high = check_surface(t.body.rest, raised, t.triangles);
  print("arms raised 150, hips 30, knees 60 (skinned)", high);
  EXPECT_TRUE(high.ok()) << high.problem;
}

TEST(SurfaceCheck, NoiseOfAThirdOfAnEdgeFails) {
  const auto& t = template_body();
  const std::vector<Vec3>& rest = t.body.rest;
  std::vector<double> edge(rest.size(), 0.0);
  std::vector<int> count(rest.size(), 0);
  for (const auto& [a, b] : unique_edges(t.triangles)) {
    const double length = (rest[static_cast<size_t>(a)] - rest[static_cast<size_t>(b)]).norm();
    edge[static_cast<size_t>(a)] += length;
    edge[static_cast<size_t>(b)] += length;
    ++count[static_cast<size_t>(a)];
    ++count[static_cast<size_t>(b)];
  }
  std::mt19937 random(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> noisy = rest;
  for (size_t v = 0; v < noisy.size(); ++v) {
    const Vec3 direction(normal(random), normal(random), normal(random));
    noisy[v] += 0.3 * edge[v] / count[v] * direction.normalized();
  }
  const SurfaceCheck c = check_surface(rest, noisy, t.triangles);
  print("noise of 30% of the edge length", c);
  EXPECT_FALSE(c.ok());
  EXPECT_GT(c.strained_fraction, 0.05);
  EXPECT_GT(c.flipped_triangles, 100);
  EXPECT_NE(c.problem.find("of the edges strained beyond 1.5x"), std::string::npos) << c.problem;
  EXPECT_EQ(c.problem.find('\n'), std::string::npos);
}

TEST(SurfaceCheck, CrumpledBodyFails) {
  // Squashed to 30% of its height and folded back and forth: most edges strained, many folds.
  const auto& t = template_body();
  std::vector<Vec3> crumpled = t.body.rest;
  for (Vec3& p : crumpled) p = Vec3(p.x(), p.y() + 80.0 * std::sin(p.z() / 30.0), 0.3 * p.z());
  const SurfaceCheck c = check_surface(t.body.rest, crumpled, t.triangles);
  print("crumpled", c);
  EXPECT_FALSE(c.ok());
  EXPECT_GT(c.strained_fraction, 0.2);
  EXPECT_GT(c.flipped_triangles, 26);
}

TEST(SurfaceCheck, ShardsFail) {
  // Five vertices pulled half a metre away: too few edges for the strained fraction, but each
  // shard's edges stretch hundreds of times.
  const auto& t = template_body();
  std::vector<Vec3> shards = t.body.rest;
  for (size_t v : {100u, 3000u, 7000u, 9000u, 12000u}) shards[v] += Vec3(0, 400, 300);
  const SurfaceCheck c = check_surface(t.body.rest, shards, t.triangles);
  print("five shards", c);
  EXPECT_LT(c.strained_fraction, 0.01);
  EXPECT_GT(c.max_stretch, 100.0);
  EXPECT_GT(c.longest_stretched_edge, 25.0);
  EXPECT_FALSE(c.ok());
  EXPECT_NE(c.problem.find("an edge stretched"), std::string::npos) << c.problem;
}

TEST(SurfaceCheck, ArmPushedThroughTheChestFails) {
  // The left arm swung across the body and into the chest (skinned): the surface crosses itself.
  const auto& t = template_body();
  const std::vector<Vec3> posed = test::posed_template([](PoseBuilder& p) {
    p.shoulder(kLeft, 150.0, 70.0);
    p.elbow(kLeft, 0.0);
  });
  const SurfaceCheck c = check_surface(t.body.rest, posed, t.triangles);
  print("left arm into the chest (skinned)", c);
  EXPECT_GT(c.self_intersecting_pairs, 150);
  EXPECT_FALSE(c.ok());
  EXPECT_NE(c.problem.find("triangles pass through the surface"), std::string::npos) << c.problem;
  // Not a strain problem: the arm is whole.
  EXPECT_LT(c.strained_fraction, 0.01);
}

TEST(SurfaceCheck, CrossingsTheReferenceHasAreNotCounted) {
  // A reference that already crosses itself (the arm in the chest) against itself, and a rigid
  // motion of it: no new crossings.
  const auto& t = template_body();
  const std::vector<Vec3> crossed = test::posed_template([](PoseBuilder& p) {
    p.shoulder(kLeft, 150.0, 70.0);
    p.elbow(kLeft, 0.0);
  });
  std::vector<Vec3> moved;
  for (const Vec3& p : crossed) moved.push_back(Vec3(p.y(), -p.x(), p.z()) + Vec3(5, 6, 7));
  const SurfaceCheck c = check_surface(crossed, moved, t.triangles, SurfaceCheckLimits::at_rest());
  EXPECT_GT(c.reference_self_intersecting_pairs, 150);
  EXPECT_EQ(c.self_intersecting_triangles, 0);
  EXPECT_TRUE(c.ok()) << c.problem;
}

}  // namespace
}  // namespace skinstream
