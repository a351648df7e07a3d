#include "core/deform/vertex_blend.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "tests/core/deform/deform_test_support.h"

namespace skinstream {
namespace {

using deform_test::deform_non_rigidly;
using deform_test::random_motion;
using deform_test::random_points;

TEST(VertexBlend, NormalizeRejectsInvalidWeightsUnchanged) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::vector<PartInfluence> bad : {std::vector<PartInfluence>{},
                                         std::vector<PartInfluence>{{0, 0.0}, {1, 0.0}},
                                         std::vector<PartInfluence>{{0, 1.0}, {1, -0.5}},
                                         std::vector<PartInfluence>{{0, nan}, {1, 1.0}}}) {
    const std::vector<PartInfluence> original = bad;
    EXPECT_FALSE(normalize_influences(bad));
    for (size_t i = 0; i < bad.size(); ++i)
      EXPECT_TRUE(bad[i].weight == original[i].weight || (std::isnan(bad[i].weight) && std::isnan(original[i].weight)));
  }
}

TEST(VertexBlend, NormalizedWeightsSumToOne) {
  std::vector<PartInfluence> influences = {{0, 2.0}, {3, 1.0}, {1, 5.0}};
  ASSERT_TRUE(normalize_influences(influences));
  EXPECT_NEAR(influences[0].weight + influences[1].weight + influences[2].weight, 1.0, 1e-15);
  EXPECT_DOUBLE_EQ(influences[2].weight, 5.0 / 8.0);
}

class VertexBlendParts : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(20);
    for (int p = 0; p < 2; ++p) {
      const std::vector<Vec3> members = random_points(rng, 15, Vec3(100, 60, 40), Vec3(200.0 * p, 0, 900));
      parts.emplace_back(build_part_model(members));
      ASSERT_TRUE(parts.back().solve(deform_non_rigidly(members, random_motion(rng))));
    }
  }
  std::vector<PartDeformer> parts;
  Vec3 vertex{100, 10, 905};
};

TEST_F(VertexBlendParts, RejectsOutOfRangePart) {
  const std::vector<PartInfluence> influences = {{2, 1.0}};
  EXPECT_FALSE(is_present(blend_vertex(vertex, influences, parts)));
}

TEST_F(VertexBlendParts, SinglePartEqualsThatPart) {
  const std::vector<PartInfluence> influences = {{1, 1.0}};
  const Vec3 expected = parts[1].deform(parts[1].model().local_from_world(vertex));
  EXPECT_LT((blend_vertex(vertex, influences, parts) - expected).norm(), 1e-12);
}

TEST_F(VertexBlendParts, TwoPartsGiveWeightedSum) {
  std::vector<PartInfluence> influences = {{0, 1.0}, {1, 3.0}};
  ASSERT_TRUE(normalize_influences(influences));
  const Vec3 a = parts[0].deform(parts[0].model().local_from_world(vertex));
  const Vec3 b = parts[1].deform(parts[1].model().local_from_world(vertex));
  EXPECT_LT((blend_vertex(vertex, influences, parts) - (0.25 * a + 0.75 * b)).norm(), 1e-9);
}

}  // namespace
}  // namespace skinstream
