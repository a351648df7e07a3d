// Marker sets: checks of a set, capture labels against sets, and where a set's markers land on a
// body (exactly, on a box whose answers are known, and on the procedural mannequin).
#include "core/fitting/marker_set.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/synth/mannequin.h"

namespace skinstream {
namespace {

MarkerPlacement point(const std::string& name, const std::string& bone, double along, const Vec3& direction,
                      std::vector<std::string> aliases = {}) {
  MarkerPlacement p;
  p.name = name;
  p.aliases = std::move(aliases);
  p.bone = bone;
  p.along = along;
  p.direction = direction;
  return p;
}

MarkerPlacement region(const std::string& pattern, std::vector<std::string> bones, int side = kAnySide) {
  MarkerPlacement p;
  p.pattern = pattern;
  p.bones = std::move(bones);
  p.side = side;
  return p;
}

MarkerSet set_of(const std::string& name, std::vector<MarkerPlacement> markers) {
  return MarkerSet{name, "test", std::move(markers)};
}

// The one-line message of validate(set), "" when it passes.
std::string problem(const MarkerSet& set) {
  try {
    validate(set);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
}

void expect_refused(MarkerSet set, const std::string& fragment) {
  const std::string message = problem(set);
  EXPECT_NE(message.find(fragment), std::string::npos) << "'" << message << "' lacks '" << fragment << "'";
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST(MarkerSetValidate, RefusesEachBrokenRuleWithOneLineNamingTheEntry) {
  const MarkerSet good = set_of("s", {point("LELB", "lowerarm01.L", 0.0, Vec3(-1, 0, 0), {"LEL"}),
                                      region("thigh_L_*", {"upperleg*.L"}, kFrontSide)});
  ASSERT_EQ(problem(good), "");

  MarkerSet s = good;
  s.name = "";
  expect_refused(s, "needs a name");
  s = good;
  s.source = "";
  expect_refused(s, "needs a source");
  s = good;
  s.markers.clear();
  expect_refused(s, "has no markers");

  s = good;
  s.markers[0].name = "";
  expect_refused(s, "entry 1: name is empty");
  s = good;
  s.markers[0].name = "L ELB";
  expect_refused(s, "entry 1 (L ELB): name holds a space");
  s = good;
  s.markers[0].name = "Actor:LELB";
  expect_refused(s, "holds ':'");
  s = good;
  s.markers[0].name = "LEL*";
  expect_refused(s, "holds '*'");
  s = good;
  s.markers[0].name = "LE\x01LB";
  expect_refused(s, "not printable ASCII");
  s = good;
  s.markers[0].aliases = {"le lb"};
  expect_refused(s, "alias 'le lb' holds a space");
  s = good;
  s.markers[0].bone = "";
  expect_refused(s, "entry 1 (LELB): has no bone");
  for (double along : {-0.01, 1.01, std::nan("")}) {
    s = good;
    s.markers[0].along = along;
    expect_refused(s, "along must be in [0, 1]");
  }
  for (const Vec3& d :
       {Vec3(0, 0, 0), Vec3(std::nan(""), 1, 0), Vec3(std::numeric_limits<double>::infinity(), 0, 0)}) {
    s = good;
    s.markers[0].direction = d;
    expect_refused(s, "direction must be finite and not zero");
  }
  for (double r : {0.0, -5.0, 500.5, std::nan("")}) {
    s = good;
    s.markers[0].radius_mm = r;
    expect_refused(s, "radius_mm must be in (0, 500]");
  }
  s = good;
  s.markers[0].bones = {"head"};
  expect_refused(s, "a point entry (name) takes a bone, not bones or a side");
  s = good;
  s.markers[0].description = "two\nlines";
  expect_refused(s, "description holds a control character");

  s = good;
  s.markers[1].pattern = "thigh_L";
  expect_refused(s, "entry 2 (thigh_L): pattern has no '*'");
  s = good;
  s.markers[1].pattern = "thigh L*";
  expect_refused(s, "pattern holds a space");
  s = good;
  s.markers[1].bones.clear();
  expect_refused(s, "entry 2 (thigh_L_*): has no bones");
  s = good;
  s.markers[1].bones = {""};
  expect_refused(s, "bone name is empty");
  s = good;
  s.markers[1].bone = "upperleg01.L";
  expect_refused(s, "a region entry (pattern) takes bones, not a name, aliases or a bone");
  s = good;
  s.markers[1].side = 2;
  expect_refused(s, "side must be front, back or any");

  // Unique within the set, case ignored, and no name a pattern also claims.
  s = good;
  s.markers.push_back(point("lelb", "lowerarm01.R", 0.0, Vec3(1, 0, 0)));
  expect_refused(s,
                 "entry 3 (lelb): name 'lelb' repeats one of marker set 's' entry 1 (LELB) (case ignored)");
  s = good;
  s.markers.push_back(point("RELB", "lowerarm01.R", 0.0, Vec3(1, 0, 0), {"LEL"}));
  expect_refused(s, "name 'LEL' repeats");
  s = good;
  s.markers.push_back(region("THIGH_L_*", {"upperleg*.L"}));
  expect_refused(s, "entry 3 (THIGH_L_*): repeats the pattern of");
  s = good;
  s.markers.push_back(point("thigh_L_1", "upperleg02.L", 0.5, Vec3(-1, 0, 0)));
  expect_refused(s, "name 'thigh_L_1' is also matched by the pattern of marker set 's' entry 2 (thigh_L_*)");
}

TEST(MarkerSetLabels, BareLabelDropsTheSubjectPrefixAndSpaces) {
  EXPECT_EQ(bare_label("Actor1:LELB"), "LELB");
  EXPECT_EQ(bare_label("  Derrick:LASI  "), "LASI");
  EXPECT_EQ(bare_label("a:b:RKNE"), "RKNE");  // the last ':' ends the prefix
  EXPECT_EQ(bare_label("LELB"), "LELB");
  EXPECT_EQ(bare_label("Q_LElbowOut"), "Q_LElbowOut");  // '_' is left to the matcher
  EXPECT_EQ(bare_label("thigh_L_3"), "thigh_L_3");
  EXPECT_EQ(bare_label("Male:"), "");
  EXPECT_EQ(bare_label(""), "");
}

std::vector<MarkerSet> two_sets() {
  return {
      set_of("vicon", {point("LELB", "lowerarm01.L", 0, Vec3(-1, 0, 0)),
                       point("RELB", "lowerarm01.R", 0, Vec3(1, 0, 0)),
                       point("RBAC", "spine01", 0.3, Vec3(1, -1, 0), {"RBAK"}),
                       point("C7", "neck01", 0, Vec3(0, -1, 0))}),
      set_of("motive", {point("LElbowOut", "lowerarm01.L", 0, Vec3(-1, 0, 0)),
                        point("RElbowOut", "lowerarm01.R", 0, Vec3(1, 0, 0)),
                        point("WaistLFront", "pelvis.L", 0.9, Vec3(0, 1, 0.5))}),
      set_of("dense", {region("thigh_L_*", {"upperleg*.L"}), region("chest_*", {"spine01"}, kFrontSide)})};
}

TEST(MarkerSetMatchTest, PicksTheSetNamingMostLabelsCaseAndPrefixIgnored) {
  const std::vector<MarkerSet> sets = two_sets();
  const std::vector<std::string> vicon = {"Male:lelb", "Male:RELB", " Male:rbak",
                                          "Male:C7",   "*3",        "Male:HEAD"};
  const MarkerSetMatch m = match_marker_set(sets, vicon);
  EXPECT_EQ(m.set, 0);
  EXPECT_EQ(m.matched, 4);
  EXPECT_EQ(m.labelled, 5);  // "*3" is an unlabelled channel
  EXPECT_TRUE(m.known());
  EXPECT_EQ(m.placement, (std::vector<int>{0, 1, 2, 3, -1, -1}));
  EXPECT_EQ(describe_match(sets, vicon, m), "vicon: 4 of 5 labelled markers named");

  // QTM and NatNet join the subject with '_': the part after it names the marker.
  const std::vector<std::string> natnet = {"Karlie_LElbowOut", "Q_RElbowOut", "My_Actor_WaistLFront",
                                           "Karlie_Nose"};
  const MarkerSetMatch n = match_marker_set(sets, natnet);
  EXPECT_EQ(n.set, 1);
  EXPECT_EQ(n.placement, (std::vector<int>{0, 1, 2, -1}));

  // Region patterns by glob; a whole name is tried before its parts after '_'.
  const std::vector<std::string> dense = {"thigh_L_1", "Sub:thigh_L_22", "chest_3", "CHEST_4", "thigh_R_1"};
  const MarkerSetMatch d = match_marker_set(sets, dense);
  EXPECT_EQ(d.set, 2);
  EXPECT_EQ(d.placement, (std::vector<int>{0, 0, 1, 1, -1}));
}

TEST(MarkerSetMatchTest, TiesGoToTheSmallerSetAndUnknownLabelsToNone) {
  std::vector<MarkerSet> sets = two_sets();
  sets.push_back(set_of("small", {point("LELB", "lowerarm01.L", 0, Vec3(-1, 0, 0))}));
  const std::vector<std::string> one = {"LELB"};
  EXPECT_EQ(match_marker_set(sets, one).set, 3);  // vicon and small name it; small is smaller

  const std::vector<std::string> unknown = {"RTH1", "RTH2", "PV1", "pv4", "LELB"};
  const MarkerSetMatch m = match_marker_set(sets, unknown);
  EXPECT_EQ(m.set, 3);
  EXPECT_EQ(m.matched, 1);
  EXPECT_FALSE(m.known());
  EXPECT_EQ(
      describe_match(sets, unknown, m),
      "no known marker set (the best, small, names 1 of 5 labelled markers); unnamed: RTH1 RTH2 PV1 pv4");

  const std::vector<std::string> none = {"RTH1", "*0"};
  const MarkerSetMatch z = match_marker_set(sets, none);
  EXPECT_EQ(z.set, -1);
  EXPECT_EQ(z.placement, (std::vector<int>{-1, -1}));
  EXPECT_FALSE(z.known());
  EXPECT_EQ(describe_match(sets, none, z), "no known marker set names any of the 1 labelled markers");
  EXPECT_FALSE(match_marker_set({}, one).known());
}

// A closed box, x and y in [-100, 100], z in [0, 400], each side split into n x n quads
// (counter-clockwise seen from outside); bone "lower" from z 0 to 200 skins the vertices below
// z = 200, "upper" the rest; bone "outside" stands beside the box at x = 300.
Body box_body(int n = 4) {
  Body body;
  const Vec3 lo(-100, -100, 0), hi(100, 100, 400);
  // Each side: a corner and two edge vectors whose cross product points outward.
  struct Side {
    Vec3 origin, u, v;
  };
  const Vec3 size = hi - lo;
  const std::array<Side, 6> sides = {{
      {Vec3(hi.x(), lo.y(), lo.z()), Vec3(0, size.y(), 0), Vec3(0, 0, size.z())},  // +X
      {Vec3(lo.x(), lo.y(), lo.z()), Vec3(0, 0, size.z()), Vec3(0, size.y(), 0)},  // -X
      {Vec3(lo.x(), hi.y(), lo.z()), Vec3(0, 0, size.z()), Vec3(size.x(), 0, 0)},  // +Y
      {Vec3(lo.x(), lo.y(), lo.z()), Vec3(size.x(), 0, 0), Vec3(0, 0, size.z())},  // -Y
      {Vec3(lo.x(), lo.y(), hi.z()), Vec3(size.x(), 0, 0), Vec3(0, size.y(), 0)},  // +Z
      {Vec3(lo.x(), lo.y(), lo.z()), Vec3(0, size.y(), 0), Vec3(size.x(), 0, 0)},  // -Z
  }};
  for (const Side& s : sides) {
    const int first = body.vertex_count();
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) body.rest.push_back(s.origin + s.u * i / n + s.v * j / n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = first + j * (n + 1) + i;
        body.faces.push_back({a, a + 1, a + n + 2, a + n + 1});
      }
  }
  body.skeleton = Skeleton({{"lower", -1, Vec3(0, 0, 0), Vec3(0, 0, 200)},
                            {"upper", 0, Vec3(0, 0, 200), Vec3(0, 0, 400)},
                            {"outside", -1, Vec3(300, 0, 100), Vec3(300, 0, 300)}});
  std::vector<std::vector<std::pair<int, double>>> lists;
  for (const Vec3& p : body.rest) lists.push_back({{p.z() < 200.0 ? 0 : 1, 1.0}});
  body.weights = SkinWeights::from_lists(lists, body.skeleton.size());
  validate(body);
  return body;
}

TEST(PlaceMarker, RefusesRegionsUnknownBonesBadRaysAndRaysThatNeverLeave) {
  const Body body = box_body();
  const std::vector<Triangle> tris = triangulate(body.faces);
  const TriangleBvh bvh(body.rest, tris);
  auto message = [&](const MarkerPlacement& p) -> std::string {
    try {
      place_marker(body, tris, bvh, p);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "placed";
  };
  EXPECT_EQ(message(region("a_*", {"lower"})), "region a_*: has no single site to place");
  EXPECT_EQ(message(point("M", "spine", 0.5, Vec3(1, 0, 0))), "marker M: bone spine is not in the skeleton");
  EXPECT_EQ(message(point("M", "lower", 1.5, Vec3(1, 0, 0))),
            "marker M: along must be in [0, 1] (0 = head joint, 1 = tail joint)");
  EXPECT_EQ(message(point("M", "lower", 0.5, Vec3(0, 0, 0))),
            "marker M: direction must be finite and not zero");
  // Beside the box, looking away from it: the ray never crosses the surface.
  EXPECT_EQ(message(point("M", "outside", 0.5, Vec3(1, 0, 0))),
            "marker M: the ray from bone outside never leaves the body");
  // Hits the +X side's second row of quads: triangles beyond the first four.
  const MarkerPlacement p = point("M", "lower", 0.5, Vec3(1, 0.4, 0.3));
  const std::vector<Triangle> fewer(tris.begin(), tris.begin() + 4);  // not the triangles the BVH holds
  EXPECT_THROW(place_marker(body, fewer, bvh, p), std::invalid_argument);
}

TEST(PlaceMarker, LandsWhereTheRayFirstLeavesTheSurface) {
  const Body body = box_body();
  const std::vector<Triangle> tris = triangulate(body.faces);
  const TriangleBvh bvh(body.rest, tris);
  struct Case {
    MarkerPlacement placement;
    Vec3 site, normal;
  };
  const std::vector<Case> cases = {
      {point("side", "lower", 0.55, Vec3(2.5, 1, 0)), Vec3(100, 40, 110), Vec3(1, 0, 0)},
      {point("back", "upper", 0.25, Vec3(0.2, -1, 0.1)), Vec3(20, -100, 260), Vec3(0, -1, 0)},
      {point("top", "upper", 0.9, Vec3(0.5, 1, 1)), Vec3(10, 20, 400), Vec3(0, 0, 1)},
      {point("bottom", "lower", 0.1, Vec3(-0.5, 0.25, -1)), Vec3(-10, 5, 0), Vec3(0, 0, -1)},
      // Starts outside: passes in through x = 100 and leaves through x = -100.
      {point("through", "outside", 0.5, Vec3(-1, 0.1, 0.1)), Vec3(-100, 40, 240), Vec3(-1, 0, 0)},
  };
  for (const Case& c : cases) {
    const SurfacePoint s = place_marker(body, tris, bvh, c.placement);
    EXPECT_LT((s.position - c.site).norm(), 1e-9) << c.placement.name << ": " << s.position.transpose();
    EXPECT_LT((s.normal - c.normal).norm(), 1e-12) << c.placement.name;
    ASSERT_GE(s.triangle, 0);
    const Triangle& t = tris[static_cast<size_t>(s.triangle)];
    const Vec3 rebuilt = s.barycentric[0] * body.rest[static_cast<size_t>(t[0])] +
                         s.barycentric[1] * body.rest[static_cast<size_t>(t[1])] +
                         s.barycentric[2] * body.rest[static_cast<size_t>(t[2])];
    EXPECT_LT((rebuilt - s.position).norm(), 1e-9) << c.placement.name;
    EXPECT_NEAR(s.barycentric.sum(), 1.0, 1e-12);
  }
}

TEST(PlaceMarker, LateralElbowMarkersLandOutsideTheMannequinsElbows) {
  const Body body = synth::make_mannequin();
  const std::vector<Triangle> tris = triangulate(body.faces);
  const TriangleBvh bvh(body.rest, tris);
  for (const char* side : {"L", "R"}) {
    const double lateral = std::string(side) == "L" ? -1.0 : 1.0;
    const std::string bone = std::string("lowerarm01.") + side;
    const SurfacePoint s = place_marker(body, tris, bvh, point("ELB", bone, 0.0, Vec3(lateral, 0, 0)));
    const Vec3 elbow = body.skeleton.bone(body.skeleton.require(bone)).head;
    EXPECT_GT(lateral * (s.position.x() - elbow.x()), 20.0) << side;  // out beyond the joint, on the skin
    EXPECT_LT((s.position - elbow).norm(), 80.0) << side;
    EXPECT_GT(lateral * s.normal.x(), 0.5) << side;
  }
}

TEST(RegionTriangles, RefusesPointEntriesAndUnknownBones) {
  const Body body = box_body();
  const std::vector<Triangle> tris = triangulate(body.faces);
  EXPECT_THROW(region_triangles(body, tris, point("M", "lower", 0.5, Vec3(1, 0, 0))), std::invalid_argument);
  try {
    region_triangles(body, tris, region("a_*", {"lower", "spine*"}));
    FAIL() << "no error for a bone glob that matches no bone";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "region a_*: bone spine* is not in the skeleton");
  }
  Body unweighted = body;
  unweighted.weights = SkinWeights{};
  EXPECT_THROW(region_triangles(unweighted, tris, region("a_*", {"lower"})), std::invalid_argument);
}

TEST(RegionTriangles, KeepsTrianglesTouchingTheBonesSkinOnTheAskedSide) {
  const Body body = box_body();
  const std::vector<Triangle> tris = triangulate(body.faces);
  auto centroid = [&](size_t t) {
    return (body.rest[static_cast<size_t>(tris[t][0])] + body.rest[static_cast<size_t>(tris[t][1])] +
            body.rest[static_cast<size_t>(tris[t][2])]) /
           3.0;
  };
  const std::vector<char> lower = region_triangles(body, tris, region("a_*", {"lower"}));
  const std::vector<char> both =
      region_triangles(body, tris, region("a_*", {"*er"}));  // a glob: lower, upper
  const std::vector<char> front = region_triangles(body, tris, region("a_*", {"upper"}, kFrontSide));
  const std::vector<char> back = region_triangles(body, tris, region("a_*", {"upper"}, kBackSide));
  ASSERT_EQ(lower.size(), tris.size());
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 c = centroid(t);
    // A triangle belongs when any of its vertices is skinned by the bones: those with a vertex
    // below z = 200 (the sides' band 100..200 included), none wholly above.
    bool touches_lower = false;
    for (int v : tris[t]) touches_lower = touches_lower || body.rest[static_cast<size_t>(v)].z() < 200.0;
    EXPECT_EQ(lower[t] != 0, touches_lower) << c.transpose();
    EXPECT_TRUE(both[t]) << c.transpose();
    // Sides by the vertex normals (each side of the box has its own vertices): +Y faces forward,
    // and so do +X, -X and the top (normal y = 0 >= -0.1); only -Y faces back.
    if (c.z() > 300.0 && (c.y() > 99.0 || std::abs(c.x()) > 99.0 || c.z() > 399.0)) {
      EXPECT_TRUE(front[t]);
      EXPECT_FALSE(back[t]);
    }
    if (c.z() > 300.0 && c.y() < -99.0) {
      EXPECT_TRUE(back[t]);
      EXPECT_FALSE(front[t]);
    }
    if (c.z() < 100.0) {  // wholly below z = 200: not the upper bone's
      EXPECT_FALSE(front[t]);
      EXPECT_FALSE(back[t]);
    }
  }
}

}  // namespace
}  // namespace skinstream
