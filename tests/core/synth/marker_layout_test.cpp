#include "core/synth/marker_layout.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <regex>
#include <set>

#include "core/synth/mannequin.h"

namespace skinstream::synth {
namespace {

struct LayoutFixture {
  Body body = make_mannequin();
  std::vector<Triangle> tris = triangulate(body.faces);
  Anatomy anatomy = Anatomy::from(body);
};
const LayoutFixture& layout_fx() {
  static const LayoutFixture f;
  return f;
}

std::vector<MarkerSite> lay(int count, uint64_t seed, LayoutOptions o = {}) {
  o.count = count;
  return layout_markers(layout_fx().body.rest, layout_fx().tris, layout_fx().body.weights, layout_fx().body.skeleton, layout_fx().anatomy, o,
                        seed);
}

std::vector<double> nearest(const std::vector<MarkerSite>& m) {
  std::vector<double> out;
  for (size_t i = 0; i < m.size(); ++i) {
    double best = 1e18;
    for (size_t j = 0; j < m.size(); ++j)
      if (i != j) best = std::min(best, (m[i].rest_position - m[j].rest_position).norm());
    out.push_back(best);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SynthMarkerLayout, RejectsCountsItCannotPlace) {
  EXPECT_THROW(lay(10, 1), std::invalid_argument);       // 10 extras need at least 11
  EXPECT_THROW(lay(1000000, 1), std::invalid_argument);  // more than the candidate vertices
  LayoutOptions o;
  o.elbow_extras = 4;
  EXPECT_THROW(lay(100, 1, o), std::invalid_argument);
  o = {};
  o.elbow_extras = 0;
  o.scapula_extras = 0;
  EXPECT_EQ(lay(1, 1, o).size(), 1u);
}

TEST(SynthMarkerLayout, ExactCountUniqueRegionNamesAndExtras) {
  const auto m = lay(200, 1);
  ASSERT_EQ(m.size(), 200u);
  std::set<std::string> names;
  const std::regex pattern("[a-z]+(_[LR])?_[0-9]+");
  int elbow_extras = 0, scapula_extras = 0;
  for (const MarkerSite& s : m) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_TRUE(std::regex_match(s.name, pattern)) << s.name;
    EXPECT_EQ(s.name.rfind(s.region + "_", 0), 0u) << s.name;
    if (s.extra && s.region.rfind("elbow_", 0) == 0) ++elbow_extras;
    if (s.extra && s.region.rfind("scapula_", 0) == 0) ++scapula_extras;
    // On the surface: the barycentric point of its triangle.
    const Triangle& t = layout_fx().tris[static_cast<size_t>(s.triangle)];
    EXPECT_NEAR(s.barycentric.sum(), 1.0, 1e-12);
    EXPECT_GE(s.barycentric.minCoeff(), 0.0);
    const Vec3 p = s.barycentric[0] * layout_fx().body.rest[static_cast<size_t>(t[0])] +
                   s.barycentric[1] * layout_fx().body.rest[static_cast<size_t>(t[1])] +
                   s.barycentric[2] * layout_fx().body.rest[static_cast<size_t>(t[2])];
    EXPECT_LT((p - s.rest_position).norm(), 1e-9);
    // Never on the head, hands or feet.
    EXPECT_EQ(s.region.find("hand"), std::string::npos);
    EXPECT_EQ(s.region.find("foot"), std::string::npos);
    EXPECT_NE(s.region, "head");
  }
  EXPECT_EQ(elbow_extras, 6);
  EXPECT_EQ(scapula_extras, 4);
  EXPECT_TRUE(names.count("elbow_L_1") && names.count("elbow_R_3") && names.count("scapula_R_2"));
  // Elbow extras sit at the back of the elbow, shoulder-blade extras on the back.
  for (const MarkerSite& s : m)
    if (s.extra) {
      EXPECT_LT(s.rest_normal.y(), 0.3) << s.name;
    }
}

TEST(SynthMarkerLayout, SpacingIsEvenAndShrinksWithTheCount) {
  const auto sparse = nearest(lay(120, 3));
  const auto dense = nearest(lay(300, 3));
  const double median_sparse = sparse[sparse.size() / 2], median_dense = dense[dense.size() / 2];
  EXPECT_LT(median_dense, median_sparse * 0.8);
  // Farthest-point sampling: few markers much closer than the typical spacing (the
  // mannequin's separate limb capsules let some come close across a gap).
  EXPECT_GT(dense[dense.size() / 10], 0.45 * median_dense);
}

TEST(SynthMarkerLayout, SameSeedSameLayoutOtherSeedAnother) {
  const auto a = lay(150, 11), b = lay(150, 11), c = lay(150, 12);
  ASSERT_EQ(a.size(), b.size());
  int moved = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].rest_position, b[i].rest_position);
    moved += (a[i].rest_position - c[i].rest_position).norm() > 1.0;
  }
  EXPECT_GT(moved, 20);
}

}  // namespace
}  // namespace skinstream::synth
