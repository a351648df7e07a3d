#include "core/offline/vertex_part_weights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/offline/marker_part_weights.h"
#include "core/offline/part_joints.h"
#include "core/offline/part_segmentation.h"
#include "tests/core/offline/offline_test_support.h"

namespace skinstream {
namespace {

constexpr int kVertexWeightFrames = 120;

struct VertexWeightsFixture {
  test::ArticulatedLimb limb = test::make_articulated_limb(3, kVertexWeightFrames);
  MarkerPartWeights alpha;
  VertexWeightsFixture() {
    // A boundary marker of parts 0 and 1 moved halfway, so that some vertices blend two parts.
    const std::vector<int> parts = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, kVertexWeightFrames,
                                                                limb.segment, AssignmentKind::PerMarker)
                                       .triangle_part;
    test::move_halfway(limb, limb.marker(3, 2), 5, kVertexWeightFrames);
    alpha = marker_part_weights(limb.reference, limb.triangles, parts, 3, limb.positions, kVertexWeightFrames);
  }
  VertexPartWeights weights(const std::vector<Vec3>& vertices, std::span<const PartJoint> joints = {},
                            std::span<const char> under_marker = {}, double joint_blend_mm = 0.0) const {
    return vertex_part_weights(vertices, limb.reference, limb.triangles, alpha.part_member_offsets, alpha.part_members,
                               joints, under_marker, false, joint_blend_mm);
  }
};

double beta(const VertexPartWeights& w, int vertex, int part) {
  for (int k = w.vertex_influence_offsets[vertex]; k < w.vertex_influence_offsets[vertex + 1]; ++k)
    if (w.vertex_influences[k].part == part) return w.vertex_influences[k].weight;
  return 0.0;
}

TEST(VertexPartWeights, RejectsBadInputs) {
  const VertexWeightsFixture f;
  const auto& l = f.limb;
  const std::vector<Vec3> vertices{Vec3(40, 0, 100)};
  EXPECT_THROW(vertex_part_weights(vertices, l.reference, {}, f.alpha.part_member_offsets, f.alpha.part_members),
               std::invalid_argument);
  auto bad = l.triangles;
  bad[0][2] = -1;
  EXPECT_THROW(vertex_part_weights(vertices, l.reference, bad, f.alpha.part_member_offsets, f.alpha.part_members),
               std::invalid_argument);
  const std::vector<Vec3> nan{Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0)};
  EXPECT_THROW(f.weights(nan), std::invalid_argument);
  std::vector<PartMember> negative = f.alpha.part_members;
  negative[0].weight = -0.5;
  EXPECT_THROW(vertex_part_weights(vertices, l.reference, l.triangles, f.alpha.part_member_offsets, negative),
               std::invalid_argument);
  const std::vector<int> short_offsets{0, 3};
  EXPECT_THROW(vertex_part_weights(vertices, l.reference, l.triangles, short_offsets, f.alpha.part_members),
               std::invalid_argument);
}

TEST(VertexPartWeights, SumToOneAndFollowTheNearestTriangle) {
  const VertexWeightsFixture f;
  const auto& l = f.limb;
  const int split = l.marker(3, 2);
  ASSERT_GT(f.alpha.weight(split, 0), 0.3);
  ASSERT_GT(f.alpha.weight(split, 1), 0.3);

  std::vector<Vec3> vertices;
  // 1: on every marker, 5 mm outside the surface.
  for (const Vec3& p : l.reference) vertices.push_back(p + 5.0 * Vec3(p.x(), p.y(), 0.0).normalized());
  const size_t on_markers = vertices.size();
  // 2: random points around the limb, near and far from the surface.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI), height(-50.0, 650.0), radius(20.0, 60.0);
  for (int k = 0; k < 2000; ++k) {
    const double a = angle(rng), r = radius(rng);
    vertices.emplace_back(r * std::cos(a), r * std::sin(a), height(rng));
  }
  const VertexPartWeights w = f.weights(vertices);
  ASSERT_EQ(w.vertex_influence_offsets.size(), vertices.size() + 1);
  for (size_t j = 0; j < vertices.size(); ++j) {
    double sum = 0.0;
    for (int k = w.vertex_influence_offsets[j]; k < w.vertex_influence_offsets[j + 1]; ++k) {
      EXPECT_GT(w.vertex_influences[k].weight, 0.0);
      sum += w.vertex_influences[k].weight;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12) << "vertex " << j;
  }
  // A vertex on a marker gets that marker's weights.
  for (size_t i = 0; i < on_markers; ++i)
    for (int p = 0; p < 3; ++p) EXPECT_NEAR(beta(w, static_cast<int>(i), p), f.alpha.weight(static_cast<int>(i), p), 1e-9) << i;
  // Inside a part (between rings 1 and 2 of segment 0, or rings 9 and 10 of segment 2): weight 1.
  const std::vector<Vec3> inside{Vec3(45.0, 3.0, 70.0), Vec3(-30.0, -30.0, 520.0)};
  const VertexPartWeights wi = f.weights(inside);
  EXPECT_EQ(wi.vertex_influence_offsets[1], 1);
  EXPECT_EQ(beta(wi, 0, 0), 1.0);
  EXPECT_EQ(beta(wi, 1, 2), 1.0);
  // Between the split marker and its ring neighbours the vertex blends parts 0 and 1.
  const Vec3 near_split = 0.8 * l.reference[split] + 0.2 * l.reference[l.marker(3, 3)];
  const VertexPartWeights ws = f.weights({near_split});
  EXPECT_GT(beta(ws, 0, 0), 0.0);
  EXPECT_GT(beta(ws, 0, 1), 0.0);
}

// A point on the limb's skin (radius 45 mm, markers at 40) at height z, between the markers
// around the ring at `around` (in marker steps, may be fractional).
Vec3 skin(double around, double z) {
  const double angle = 2.0 * M_PI * around / 8.0;
  return Vec3(45.0 * std::cos(angle), 45.0 * std::sin(angle), z);
}

// The limb's first joint is at z = 200, between ring 3 (z = 175, segment 0) and ring 4 (z = 225,
// segment 1). The nearest triangle of skin just past it has markers of both segments.
TEST(VertexPartWeights, SkinPastAJointFollowsThePartBeyondIt) {
  const VertexWeightsFixture f;
  const auto& l = f.limb;
  const std::vector<PartJoint> joints =
      fit_part_joints(l.reference, f.alpha.part_member_offsets, f.alpha.part_members, l.positions, kVertexWeightFrames);
  ASSERT_EQ(joints.size(), 2u);
  const std::vector<Vec3> vertices{skin(5.5, 210.0), skin(5.5, 190.0)};
  const VertexPartWeights paper = f.weights(vertices), split = f.weights(vertices, joints);
  // The nearest triangle alone blends the two segments on both sides of the joint.
  EXPECT_GT(beta(paper, 0, 0), 0.1);
  EXPECT_GT(beta(paper, 1, 1), 0.1);
  // Split at the joint, each follows its own side's part only.
  EXPECT_NEAR(beta(split, 0, 1), 1.0, 1e-12);
  EXPECT_NEAR(beta(split, 1, 0), 1.0, 1e-12);
  // Under a marker, the markers' own weights stand.
  const std::vector<char> under{1, 0};
  const VertexPartWeights kept = f.weights(vertices, joints, under);
  for (int p = 0; p < 3; ++p) EXPECT_EQ(beta(kept, 0, p), beta(paper, 0, p)) << p;
  EXPECT_NEAR(beta(kept, 1, 0), 1.0, 1e-12);
}

// A marker that lies past the joint's plane yet moves with the part before it (an elbow marker
// slightly below the pivot) speaks for the skin up to its own height, not beyond.
TEST(VertexPartWeights, AMarkerPastTheJointSpeaksForTheSkinUpToItself) {
  const VertexWeightsFixture f;
  PartJoint low;  // a plane at z = 150: ring 3 (z = 175, segment 0) lies 25 mm past it
  low.first = 0;
  low.second = 1;
  low.centre = Vec3(0.0, 0.0, 150.0);
  low.axis = Vec3::UnitZ();
  const std::vector<PartJoint> joints{low};
  const int ring3 = f.limb.marker(3, 5);
  ASSERT_EQ(f.alpha.weight(ring3, 0), 1.0);
  // By the ring-3 marker, a little below it: its part (all but the small share of the ring-2
  // markers, which lie behind the plane and so cannot speak for skin past it).
  const std::vector<Vec3> below{skin(5.0, 172.0)};
  EXPECT_GT(beta(f.weights(below, joints), 0, 0), 0.9);
  // Beyond it (and the joint): what ring 3 says for segment 0 goes to segment 1.
  const std::vector<Vec3> beyond{skin(5.5, 200.0)};
  EXPECT_GT(beta(f.weights(beyond), 0, 0), 0.1);
  EXPECT_NEAR(beta(f.weights(beyond, joints), 0, 1), 1.0, 1e-12);
}

// With a ramp 20 mm either side of the plane at z = 200 (ring 3 at 175, all segment 0; ring 4 at
// 225, all segment 1), the skin between the rings goes from segment 0 to segment 1 linearly:
// half each on the plane, as a hinge's crease follows the bisector.
TEST(VertexPartWeights, SkinAtAJointBlendsBothPartsOverARamp) {
  const VertexWeightsFixture f;
  PartJoint joint;
  joint.first = 0;
  joint.second = 1;
  joint.centre = Vec3(0.0, 0.0, 200.0);
  joint.axis = Vec3::UnitZ();
  const std::vector<PartJoint> joints{joint};
  const std::vector<double> heights{180.0, 190.0, 200.0, 210.0, 220.0};
  const std::vector<double> expected{0.0, 0.25, 0.5, 0.75, 1.0};  // segment 1's share
  std::vector<Vec3> vertices;
  for (double z : heights) vertices.push_back(skin(5.5, z));
  const VertexPartWeights ramp = f.weights(vertices, joints, {}, 20.0), hard = f.weights(vertices, joints);
  for (size_t v = 0; v < heights.size(); ++v) {
    const int j = static_cast<int>(v);
    EXPECT_NEAR(beta(ramp, j, 1), expected[v], 1e-12) << heights[v];
    EXPECT_NEAR(beta(ramp, j, 0) + beta(ramp, j, 1), 1.0, 1e-12) << heights[v];
  }
  // Without the ramp: the hard switch at the plane.
  EXPECT_NEAR(beta(hard, 1, 0), 1.0, 1e-12);
  EXPECT_NEAR(beta(hard, 3, 1), 1.0, 1e-12);
  // Under a marker the markers' own weights still stand.
  std::vector<char> under(vertices.size(), 0);
  under[2] = 1;
  const VertexPartWeights kept = f.weights(vertices, joints, under, 20.0), paper = f.weights(vertices);
  for (int p = 0; p < 3; ++p) EXPECT_EQ(beta(kept, 2, p), beta(paper, 2, p)) << p;
  EXPECT_THROW(f.weights(vertices, joints, {}, -1.0), std::invalid_argument);
  EXPECT_THROW(f.weights(vertices, joints, {}, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
}

TEST(VertexPartWeights, RejectsBadJointsAndFlags) {
  const VertexWeightsFixture f;
  const std::vector<Vec3> vertices{skin(1.0, 100.0)};
  PartJoint bad;
  bad.first = 0;
  bad.second = 3;  // 3 parts: 0, 1, 2
  EXPECT_THROW(f.weights(vertices, std::vector<PartJoint>{bad}), std::invalid_argument);
  const std::vector<char> two_flags{0, 0};
  EXPECT_THROW(f.weights(vertices, {}, two_flags), std::invalid_argument);
}

// Two parallel sheets of markers, 60 mm apart, each one part: the skin of a fold between them
// (an armpit, a groin) as the blend across folds sees it.
struct Fold {
  std::vector<Vec3> markers;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> offsets{0};
  std::vector<PartMember> members;
  Fold() {
    for (int sheet = 0; sheet < 2; ++sheet) {
      const int first = static_cast<int>(markers.size());
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) markers.emplace_back(40.0 * i, 40.0 * j, 60.0 * sheet);
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
          const int a = first + 3 * i + j;
          triangles.push_back({a, a + 3, a + 4});
          triangles.push_back({a, a + 4, a + 1});
        }
      for (int k = 0; k < 9; ++k) members.push_back({first + k, 1.0});
      offsets.push_back(static_cast<int>(members.size()));
    }
  }
  VertexPartWeights weights(const std::vector<Vec3>& vertices, bool blend_folds, std::span<const char> under = {}) const {
    return vertex_part_weights(vertices, markers, triangles, offsets, members, {}, under, blend_folds);
  }
};

TEST(VertexPartWeights, SkinInAFoldSharesBothSidesByDistance) {
  const Fold fold;
  const std::vector<Vec3> vertices = {
      {40, 40, 30},   // the middle: half each, whichever sheet is taken as the nearest
      {40, 40, 20},   // 20 and 40 mm: ratio 2
      {40, 40, 12},   // 12 and 48 mm: ratio 4, past the limit of 3
      {40, 40, -10},  // outside the fold: both sheets the same way, nothing across
      {40, 40, 29.9}, {40, 40, 30.1}};
  const VertexPartWeights w = fold.weights(vertices, true);
  for (int v = 0; v < static_cast<int>(vertices.size()); ++v) EXPECT_NEAR(beta(w, v, 0) + beta(w, v, 1), 1.0, 1e-12) << v;
  EXPECT_NEAR(beta(w, 0, 0), 0.5, 1e-12);
  EXPECT_NEAR(beta(w, 0, 1), 0.5, 1e-12);
  // near / (near + far) * (3 - ratio) / 2 = 1/6, then the fade below 0.05: 0.5 (1/6 - 0.05) / 0.45.
  EXPECT_NEAR(beta(w, 1, 1), 0.5 * (1.0 / 6.0 - 0.05) / 0.45, 1e-12);
  EXPECT_EQ(beta(w, 2, 0), 1.0);
  EXPECT_EQ(beta(w, 3, 0), 1.0);
  // Continuous where the nearest sheet changes.
  EXPECT_NEAR(beta(w, 4, 1), beta(w, 5, 0), 1e-12);
  EXPECT_NEAR(beta(w, 4, 1), 0.5, 0.01);
  // The vertices the blend changed are flagged (what fold_weight_smoothing re-solves).
  const std::vector<char> in_fold{1, 1, 0, 0, 1, 1};
  EXPECT_EQ(w.in_fold, in_fold);

  // Without the blend, or under a marker: the nearest sheet alone.
  const VertexPartWeights plain = fold.weights(vertices, false);
  EXPECT_EQ(beta(plain, 1, 0), 1.0);
  EXPECT_EQ(beta(plain, 4, 0), 1.0);
  EXPECT_EQ(beta(plain, 5, 1), 1.0);
  std::vector<char> under(vertices.size(), 0);
  under[1] = 1;
  const VertexPartWeights kept = fold.weights(vertices, true, under);
  EXPECT_EQ(beta(kept, 1, 0), 1.0);
  EXPECT_NEAR(beta(kept, 0, 1), 0.5, 1e-12);
  EXPECT_EQ(kept.in_fold[1], 0);
  EXPECT_EQ(plain.in_fold, std::vector<char>(vertices.size(), 0));
}

// A hinge joint whose plane lies below both sheets (a hard switch): every marker gives the skin
// above its own height to the second part, so both sides of the fold weigh a vertex between the
// sheets alike, and the blend, though it takes a share of the far sheet, changes nothing.
TEST(VertexPartWeights, AFoldTheJointSplitAlreadyDecidedIsNotFlagged) {
  const Fold fold;
  const PartJoint joint{0, 1, Vec3(40, 40, -100), Vec3::UnitZ()};
  const std::vector<Vec3> vertices = {{40, 40, 20}, {40, 40, 30}};
  const VertexPartWeights w = vertex_part_weights(vertices, fold.markers, fold.triangles, fold.offsets, fold.members,
                                                  {&joint, 1}, {}, true, 0.0);
  for (int v = 0; v < 2; ++v) {
    EXPECT_EQ(beta(w, v, 1), 1.0) << v;
    EXPECT_EQ(w.in_fold[v], 0) << v;
  }
}

TEST(VerticesUnderMarkers, FlagsTheCornersOfTheFaceEachMarkerSitsOn) {
  // Two faces side by side in the z = 0 plane; one marker 4 mm above the second.
  const std::vector<Vec3> vertices{Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), Vec3(10, 10, 0)};
  const std::vector<std::array<int, 3>> faces{{0, 1, 2}, {1, 3, 2}};
  const std::vector<Vec3> markers{Vec3(8, 8, 4)};
  EXPECT_EQ(vertices_under_markers(vertices, faces, markers), (std::vector<char>{0, 1, 1, 1}));
  EXPECT_THROW(vertices_under_markers(vertices, {}, markers), std::invalid_argument);
  const std::vector<std::array<int, 3>> bad{{0, 1, 4}};
  EXPECT_THROW(vertices_under_markers(vertices, bad, markers), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
