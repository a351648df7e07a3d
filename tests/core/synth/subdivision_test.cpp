#include "core/synth/subdivision.h"

#include <gtest/gtest.h>

#include <set>

#include "core/synth/mannequin.h"
#include "core/body/skinning.h"

namespace skinstream::synth {
namespace {

Body cube() {
  Body b;
  b.rest = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  b.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  b.skeleton = Skeleton({{"a", -1, Vec3(0, 0, 0), Vec3(0, 0, 1)}, {"b", 0, Vec3(0, 0, 1), Vec3(0, 0, 2)}});
  std::vector<std::vector<std::pair<int, double>>> rows;
  for (const Vec3& p : b.rest) rows.push_back({{0, 1.0 - p.z()}, {1, p.z()}});
  b.weights = SkinWeights::from_lists(rows, 2);
  return b;
}

TEST(SynthSubdivision, RejectsAnInvalidBody) {
  Body b = cube();
  b.faces[0][1] = 99;
  EXPECT_THROW(subdivide(b), std::invalid_argument);
  b = cube();
  b.weights = SkinWeights::from_lists({{{0, 1.0}}}, 2);
  EXPECT_THROW(subdivide(b), std::invalid_argument);
}

TEST(SynthSubdivision, CubeBecomesTwentySixVerticesAndTwentyFourQuads) {
  std::vector<int> parent;
  const Body s = subdivide(cube(), &parent);
  EXPECT_EQ(s.vertex_count(), 8 + 12 + 6);
  EXPECT_EQ(s.faces.size(), 24u);
  ASSERT_EQ(parent.size(), 24u);
  for (int f = 0; f < 6; ++f) EXPECT_EQ(std::count(parent.begin(), parent.end(), f), 4);
  for (int v = 0; v < 8; ++v)
    EXPECT_TRUE(s.rest[static_cast<size_t>(v)].isApprox(cube().rest[static_cast<size_t>(v)]));
  EXPECT_NEAR(signed_volume(s.rest, triangulate(s.faces)), 1.0, 1e-12);  // same surface, same orientation
  // Weights of the new vertices are averages: the bottom corners are all "a", the top ones
  // all "b", so the midpoint of a vertical edge is half and half and the top centre all "b".
  int checked = 0;
  for (int v = 8; v < s.vertex_count(); ++v) {
    const Vec3& p = s.rest[static_cast<size_t>(v)];
    if (p.isApprox(Vec3(0, 0, 0.5))) {
      EXPECT_NEAR(s.weights.weight(v, 0), 0.5, 1e-12);
      EXPECT_NEAR(s.weights.weight(v, 1), 0.5, 1e-12);
      ++checked;
    }
    if (p.isApprox(Vec3(0.5, 0.5, 1.0))) {
      EXPECT_NEAR(s.weights.weight(v, 1), 1.0, 1e-12);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
}

TEST(SynthSubdivision, RigidPartsStayRigidAndTheMannequinQuadruplesItsFaces) {
  const Body m = make_mannequin();
  std::vector<int> parent;
  const Body s = subdivide(m, &parent);
  EXPECT_EQ(s.faces.size(), 4 * m.faces.size() - std::count_if(m.faces.begin(), m.faces.end(),
                                                               [](const Face& f) { return f[3] < 0; }));
  // Move every bone by the same rigid motion: the subdivided skin moves rigidly too.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotation(Vec3(1, 1, 0), 0.7).toRotationMatrix();
  t.translation() = Vec3(10, -20, 30);
  const BoneTransforms bones(static_cast<size_t>(s.skeleton.size()), t);
  const auto posed = skin(s.rest, s.weights, bones);
  for (size_t v = 0; v < posed.size(); v += 97) EXPECT_TRUE(posed[v].isApprox(t * s.rest[v], 1e-9));
}

}  // namespace
}  // namespace skinstream::synth
