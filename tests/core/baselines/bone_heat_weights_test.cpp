#include "core/baselines/bone_heat_weights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace skinstream {
namespace {

// A closed tube along z (radius 40 mm, 400 mm long, capped), as a limb: `around` x `along`
// vertices on the side, one centre vertex per cap.
struct Tube {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  static constexpr int around = 24, along = 41;
  static constexpr double radius = 40.0, length = 400.0;

  Tube() {
    for (int l = 0; l < along; ++l)
      for (int a = 0; a < around; ++a) {
        const double angle = 2.0 * M_PI * a / around;
        vertices.emplace_back(radius * std::cos(angle), radius * std::sin(angle), length * l / (along - 1));
      }
    auto at = [](int l, int a) { return l * around + (a % around); };
    for (int l = 0; l + 1 < along; ++l)
      for (int a = 0; a < around; ++a) {
        triangles.push_back({at(l, a), at(l, a + 1), at(l + 1, a + 1)});
        triangles.push_back({at(l, a), at(l + 1, a + 1), at(l + 1, a)});
      }
    const int bottom = static_cast<int>(vertices.size()), top = bottom + 1;
    vertices.emplace_back(0.0, 0.0, 0.0);
    vertices.emplace_back(0.0, 0.0, length);
    for (int a = 0; a < around; ++a) {
      triangles.push_back({bottom, at(0, a + 1), at(0, a)});
      triangles.push_back({top, at(along - 1, a), at(along - 1, a + 1)});
    }
  }
};

// Two bones meeting half way, each its own group: an elbow.
const std::vector<HeatBone> kElbow = {{Vec3(0, 0, 0), Vec3(0, 0, 200), 0}, {Vec3(0, 0, 200), Vec3(0, 0, 400), 1}};

double weight_of(const std::vector<int>& offsets, const std::vector<PartInfluence>& weights, int v, int group) {
  for (int k = offsets[v]; k < offsets[v + 1]; ++k)
    if (weights[k].part == group) return weights[k].weight;
  return 0.0;
}

TEST(BoneHeatWeights, RejectsNoBonesAGroupOutOfRangeAndABadTriangle) {
  const Tube tube;
  std::vector<int> offsets;
  std::vector<PartInfluence> weights;
  EXPECT_THROW(bone_heat_weights(tube.vertices, tube.triangles, {}, 1, {}, offsets, weights), std::invalid_argument);
  EXPECT_THROW(bone_heat_weights(tube.vertices, tube.triangles, kElbow, 1, {}, offsets, weights), std::invalid_argument);
  std::vector<Triangle> bad = tube.triangles;
  bad.push_back({0, 1, static_cast<int>(tube.vertices.size())});
  EXPECT_THROW(bone_heat_weights(tube.vertices, bad, kElbow, 2, {}, offsets, weights), std::invalid_argument);
}

// Each vertex's weights sum to 1; far from the joint a vertex follows its own bone alone, at the
// joint the two bones share it equally (the tube is symmetric about it), and in between the
// upper bone's share grows steadily along the limb.
TEST(BoneHeatWeights, ATubeFollowsItsNearBoneAndBlendsAcrossTheJoint) {
  const Tube tube;
  std::vector<int> offsets;
  std::vector<PartInfluence> weights;
  bone_heat_weights(tube.vertices, tube.triangles, kElbow, 2, {}, offsets, weights);
  ASSERT_EQ(offsets.size(), tube.vertices.size() + 1);
  for (size_t v = 0; v < tube.vertices.size(); ++v) {
    double sum = 0.0;
    for (int k = offsets[v]; k < offsets[v + 1]; ++k) {
      EXPECT_GE(weights[k].weight, 0.01);
      sum += weights[k].weight;
    }
    EXPECT_NEAR(sum, 1.0, 1e-9) << "vertex " << v;
  }
  double previous_upper = -1.0;
  for (int l = 0; l < Tube::along; ++l) {
    double upper = 0.0;
    for (int a = 0; a < Tube::around; ++a) upper += weight_of(offsets, weights, l * Tube::around + a, 1) / Tube::around;
    const double z = Tube::length * l / (Tube::along - 1);
    if (z <= 100.0) {
      EXPECT_LT(upper, 0.05) << "z " << z;
    }
    if (z >= 300.0) {
      EXPECT_GT(upper, 0.95) << "z " << z;
    }
    if (z == 200.0) {
      EXPECT_NEAR(upper, 0.5, 0.02);
    }
    EXPECT_GE(upper, previous_upper - 1e-9) << "z " << z;
    previous_upper = upper;
  }
}

}  // namespace
}  // namespace skinstream
