// Marker-set files: malformed files refused with one line each; the shipped sets in
// config/marker_sets/ load, land on the MakeHuman template where their names say, name the real
// captures' labels, and (Plug-in Gait) give segment widths like those of a real standing actor.
#include "protocol/offline/marker_set_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/body/anatomy.h"
#include "core/fitting/marker_set.h"
#include "core/geometry/triangle_bvh.h"
#include "core/render/software_rasterizer.h"
#include "core/synth/marker_layout.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/file_error.h"
#include "protocol/offline/makehuman.h"
#include "protocol/research/png_file.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

std::string write_set(const std::string& name, const std::string& text) {
  const std::string path = test::scratch_path(name);
  test::write_bytes(path, text);
  return path;
}

// A valid file, then the same with one thing broken: each refusal is one line naming the file,
// the entry and what is wrong.
const char* kGood = R"({"name": "Test set", "source": "this test",
  "markers": [
    {"name": "LELB", "aliases": ["LEL"], "description": "left elbow", "bone": "lowerarm01.L", "along": 0.0,
     "direction": [-2, 0, 0], "radius_mm": 25},
    {"name": "C7", "bone": "neck01", "direction": [0, -1, 0.2]},
    {"pattern": "thigh_L_*", "bones": ["upperleg*.L"], "side": "front"}
  ]})";

std::string broken(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(MarkerSetFile, RefusesMalformedFilesWithOneLineEach) {
  struct Case {
    std::string text, fragment;
  };
  const std::string e1 = "marker set 'Test set' entry 1 (LELB): ",
                    e3 = "marker set 'Test set' entry 3 (thigh_L_*): ";
  const std::vector<Case> cases = {
      {"", "not valid JSON"},
      {"{\"name\": \"x\",", "not valid JSON"},
      {"[1, 2]", "the marker set: must be a JSON object"},
      {broken("\"source\": \"this test\",", ""), "the marker set: has no \"source\""},
      {broken("\"name\": \"Test set\"", "\"name\": 7"), "the marker set: \"name\" must be a string"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"source\": \"b\","),
       "key 'source' appears twice in one object"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"author\": \"b\","),
       "the marker set: unknown key 'author'"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"notes\": [1],"),
       "the marker set: \"notes\" must be a string"},
      {broken("\"markers\": [", "\"markers\": {\"a\": ["), "not valid JSON"},
      {R"({"name": "n", "source": "s", "markers": {}})", "the marker set: \"markers\" must be an array"},
      {R"({"name": "n", "source": "s", "markers": []})", "marker set 'n': has no markers"},
      {R"({"name": "n", "source": "s", "markers": [3]})", "marker set 'n' entry 1: must be a JSON object"},
      {broken("\"name\": \"C7\", ", ""),
       "marker set 'Test set' entry 2: needs either \"name\" (one marker) or \"pattern\" (a region)"},
      {broken("\"pattern\": \"thigh_L_*\",", "\"pattern\": \"thigh_L_*\", \"name\": \"T\","),
       "needs either \"name\""},
      {broken("\"aliases\": [\"LEL\"]", "\"aliases\": \"LEL\""),
       e1 + "\"aliases\" must be an array of strings"},
      {broken("\"aliases\": [\"LEL\"]", "\"aliases\": [\"LEL\", 4]"),
       e1 + "\"aliases\" must be an array of strings"},
      {broken("\"along\": 0.0", "\"along\": \"0\""), e1 + "\"along\" must be a finite number"},
      {broken("\"along\": 0.0", "\"along\": 1e400"),
       "not valid JSON: [json.exception.out_of_range.406] number overflow"},
      {broken("\"along\": 0.0", "\"along\": 1.5"), e1 + "along must be in [0, 1]"},
      {broken("[-2, 0, 0]", "[-2, 0]"), e1 + "\"direction\" must be 3 finite numbers"},
      {broken("[-2, 0, 0]", "[-2, \"0\", 0]"), e1 + "\"direction\" must be 3 finite numbers"},
      {broken("[-2, 0, 0]", "[0, 0, 0]"), e1 + "\"direction\" must not be zero"},
      {broken("\"direction\": [-2, 0, 0], ", ""), e1 + "has no \"direction\""},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 0"), e1 + "radius_mm must be in (0, 500]"},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 501"), e1 + "radius_mm must be in (0, 500]"},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 25, \"diretion\": [1, 0, 0]"),
       e1 + "unknown key 'diretion'"},
      {broken("\"bone\": \"lowerarm01.L\", ", ""), e1 + "has no \"bone\""},
      {broken("\"name\": \"LELB\"", "\"name\": \"L ELB\""), "entry 1 (L ELB): name holds a space"},
      {broken("\"name\": \"LELB\"", "\"name\": \"Sub:LELB\""), "entry 1 (Sub:LELB): name holds ':'"},
      {broken("\"name\": \"C7\"", "\"name\": \"lelb\""),
       "entry 2 (lelb): name 'lelb' repeats one of marker set 'Test set' entry 1 (LELB)"},
      {broken("\"name\": \"C7\"", "\"name\": \"thigh_L_9\""),
       "name 'thigh_L_9' is also matched by the pattern of"},
      {broken("\"thigh_L_*\"", "\"thigh_L\""), "entry 3 (thigh_L): pattern has no '*'"},
      {broken("\"bones\": [\"upperleg*.L\"]", "\"bones\": []"), e3 + "has no bones"},
      {broken("\"bones\": [\"upperleg*.L\"]", "\"bone\": \"upperleg01.L\""), e3 + "has no \"bones\""},
      {broken("\"side\": \"front\"", "\"side\": \"left\""),
       e3 + "\"side\" must be \"front\", \"back\" or \"any\", not 'left'"},
      {broken("\"side\": \"front\"", "\"side\": \"front\", \"radius_mm\": 20"),
       e3 + "unknown key 'radius_mm'"},
      {broken("\"description\": \"left elbow\"", "\"description\": \"left\\nelbow\""),
       e1 + "description holds a control character"},
  };
  ASSERT_NO_THROW(read_marker_set(write_set("good.json", kGood)));
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = write_set("bad" + std::to_string(i) + ".json", cases[i].text);
    EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(path); }, path, cases[i].fragment))
        << "case " << i;
  }
  // A name with a terminal escape is quoted printably: the message stays one line.
  const std::string escaped =
      write_set("escape.json", broken("\"name\": \"LELB\"", "\"name\": \"L\\u001b[2J\""));
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(escaped); }, escaped, "not printable ASCII"));
}

TEST(MarkerSetFile, RefusesMissingFilesAndBadFolders) {
  const std::string missing = test::scratch_path("no_such_set.json");
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(missing); }, missing, "cannot open"));
  const std::string no_folder = test::scratch_path("no_such_folder");
  EXPECT_TRUE(
      test::throws_file_error([&] { read_marker_sets(no_folder); }, no_folder, "cannot read the folder"));
  const std::string empty = test::scratch_path("empty_sets");
  std::filesystem::create_directories(empty);
  test::write_bytes(empty + "/readme.txt", "not a set");
  EXPECT_TRUE(
      test::throws_file_error([&] { read_marker_sets(empty); }, empty, "holds no marker set (*.json)"));
  const std::string twice = test::scratch_path("twice_sets");
  std::filesystem::create_directories(twice);
  test::write_bytes(twice + "/a.json", kGood);
  test::write_bytes(twice + "/b.json", broken("\"Test set\"", "\"TEST SET\""));
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_sets(twice); }, twice + "/b.json",
                                      "marker set 'TEST SET' is also defined in " + twice + "/a.json"));
  const std::string bad_inside = test::scratch_path("bad_sets");
  std::filesystem::create_directories(bad_inside);
  test::write_bytes(bad_inside + "/a.json", kGood);
  test::write_bytes(bad_inside + "/b.json", "{");
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_sets(bad_inside); }, bad_inside + "/b.json",
                                      "not valid JSON"));
}

TEST(MarkerSetFile, ReadsEveryFieldWithItsDefaults) {
  const MarkerSet set = read_marker_set(write_set("fields.json", kGood));
  EXPECT_EQ(set.name, "Test set");
  EXPECT_EQ(set.source, "this test");
  ASSERT_EQ(set.markers.size(), 3u);
  const MarkerPlacement& elbow = set.markers[0];
  EXPECT_EQ(elbow.name, "LELB");
  EXPECT_EQ(elbow.aliases, std::vector<std::string>{"LEL"});
  EXPECT_EQ(elbow.description, "left elbow");
  EXPECT_EQ(elbow.bone, "lowerarm01.L");
  EXPECT_EQ(elbow.along, 0.0);
  EXPECT_EQ(elbow.direction, Vec3(-1, 0, 0));  // normalised
  EXPECT_EQ(elbow.radius_mm, 25.0);
  const MarkerPlacement& c7 = set.markers[1];
  EXPECT_EQ(c7.along, 0.5);
  EXPECT_EQ(c7.radius_mm, 30.0);
  EXPECT_NEAR(c7.direction.norm(), 1.0, 1e-15);
  EXPECT_TRUE(c7.aliases.empty());
  const MarkerPlacement& thigh = set.markers[2];
  EXPECT_TRUE(thigh.is_region());
  EXPECT_EQ(thigh.pattern, "thigh_L_*");
  EXPECT_EQ(thigh.bones, std::vector<std::string>{"upperleg*.L"});
  EXPECT_EQ(thigh.side, kFrontSide);
}

// ---- The shipped sets on the template ----

const std::vector<MarkerSet>& shipped() {
  static const std::vector<MarkerSet> sets = read_marker_sets(test::source_path("config/marker_sets"));
  return sets;
}

int set_index(const std::string& name) {
  for (size_t i = 0; i < shipped().size(); ++i)
    if (shipped()[i].name == name) return static_cast<int>(i);
  ADD_FAILURE() << "no shipped set " << name;
  return -1;
}

struct Template {
  Body body;
  std::vector<Triangle> triangles;
  TriangleBvh bvh;
};

const Template& makehuman() {
  static const Template t = [] {
    Template m;
    m.body = load_makehuman(test::shared_path("data/meshes/makehuman"));
    m.triangles = triangulate(m.body.faces);
    m.bvh = TriangleBvh(m.body.rest, m.triangles);
    return m;
  }();
  return t;
}

const std::string kPlugInGait = "Vicon Plug-in Gait (full body)";
const std::string kCmu = "CMU / HDM05 41-marker set";
const std::string kOptiTrack = "OptiTrack Motive Baseline (37)";
const std::string kQualisys = "Qualisys Sports Marker Set";
const std::string kDense = "skinstream dense layout (350 markers)";

TEST(MarkerSetFile, ShippedSetsLoad) {
  const std::map<std::string, size_t> entries = {
      {kPlugInGait, 44}, {kCmu, 41}, {kOptiTrack, 37}, {kQualisys, 41}, {kDense, 25}};
  ASSERT_EQ(shipped().size(), entries.size());
  for (const MarkerSet& s : shipped()) {
    ASSERT_TRUE(entries.count(s.name)) << s.name;
    EXPECT_EQ(s.markers.size(), entries.at(s.name)) << s.name;
    EXPECT_FALSE(s.source.empty()) << s.name;
    for (const MarkerPlacement& p : s.markers)
      EXPECT_EQ(p.is_region(), s.name == kDense) << s.name << " " << p.name;
  }
}

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }
bool has(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

// The side a vendor's name says: "LELB", "LShoulderTop", "WaistLFront", "HeadL", "BackLeft".
int named_side(const std::string& n) {
  const bool upper_next = n.size() > 1 && std::isupper(static_cast<unsigned char>(n[1]));
  if ((n[0] == 'L' && upper_next) || starts_with(n, "WaistL") || starts_with(n, "HeadL") || has(n, "Left"))
    return -1;
  if ((n[0] == 'R' && upper_next) || starts_with(n, "WaistR") || starts_with(n, "HeadR") || has(n, "Right"))
    return 1;
  return 0;
}

// Front or back of the body as the name says, 0 when it does not say.
int named_face(const std::string& n) {
  for (const char* front : {"Front", "FHD", "ASI", "FWT", "SHN", "Shin", "CLAV", "STRN", "Chest"})
    if (has(n, front)) return 1;
  for (const char* back :
       {"Back", "BHD", "PSI", "BWT", "SACR", "C7", "T10", "Spine", "BAK", "BAC", "HEE", "Heel"})
    if (has(n, back)) return -1;
  return 0;
}

Vec3 bone_point(const Body& body, const MarkerPlacement& p) {
  const Bone& b = body.skeleton.bone(body.skeleton.require(p.bone));
  return b.head + p.along * (b.tail - b.head);
}

double segment_distance(const Vec3& p, const Bone& b) {
  const Vec3 ab = b.tail - b.head;
  const double t = std::clamp((p - b.head).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (b.head + t * ab)).norm();
}

TEST(MarkerSetFile, ShippedSetsLandOnTheTemplate) {
  const Template& t = makehuman();
  const Skeleton& sk = t.body.skeleton;
  const double neck_top = sk.bone(sk.require("head")).head.z();
  int placed = 0, faced = 0;
  double farthest = 0.0;
  std::string farthest_name;
  for (const MarkerSet& set : shipped()) {
    std::map<std::string, SurfacePoint> sites;
    for (const MarkerPlacement& p : set.markers) {
      if (p.is_region()) continue;
      const std::string what = set.name + " " + p.name;
      SurfacePoint s;
      ASSERT_NO_THROW(s = place_marker(t.body, t.triangles, t.bvh, p)) << what;
      sites[p.name] = s;
      ++placed;
      // On the skin, near its bone: a marker is a few centimetres from the bone it rides on,
      // never across the body (the chest is the deepest: the sternum 14 cm in front of the spine).
      const double d = segment_distance(s.position, sk.bone(sk.require(p.bone)));
      EXPECT_GT(d, 3.0) << what;
      EXPECT_LT(d, 160.0) << what;
      if (d > farthest) farthest = d, farthest_name = what;
      EXPECT_LT(t.bvh.closest(s.position), 1e-6) << what;
      EXPECT_GT(s.normal.dot(p.direction), 0.0) << what;  // an exit
      // The side the name says; unsided names on the midline (HeadSide may be on either side).
      const int side = named_side(p.name);
      if (side < 0) {
        EXPECT_LT(s.position.x(), -20.0) << what;
      }
      if (side > 0) {
        EXPECT_GT(s.position.x(), 20.0) << what;
      }
      if (side == 0 && p.name != "HeadSide") {
        EXPECT_LT(std::abs(s.position.x()), 15.0) << what;
        // Front markers in front of their bone, back markers behind it.
      }
      const double ahead = s.position.y() - bone_point(t.body, p).y();
      if (named_face(p.name) > 0) {
        EXPECT_GT(ahead, 10.0) << what;
      }
      if (named_face(p.name) < 0) {
        EXPECT_LT(ahead, -10.0) << what;
      }
      faced += named_face(p.name) != 0;
      // Head markers above the neck.
      if (has(p.name, "HD") || starts_with(p.name, "Head")) {
        EXPECT_GT(s.position.z(), neck_top) << what;
      }
    }
    // A left marker and its right twin placed alike land as mirror images (the template is
    // symmetric); Plug-in Gait's upper arm and forearm markers are set apart on purpose.
    for (const MarkerPlacement& p : set.markers) {
      if (p.is_region() || named_side(p.name) >= 0) continue;
      for (const MarkerPlacement& q : set.markers) {
        if (q.is_region() || named_side(q.name) <= 0 || q.bone.back() != 'R' || p.bone.back() != 'L')
          continue;
        const std::string mirrored_bone = p.bone.substr(0, p.bone.size() - 1) + "R";
        if (q.bone != mirrored_bone || q.along != p.along ||
            q.direction != Vec3(-p.direction.x(), p.direction.y(), p.direction.z()))
          continue;
        const Vec3 a = sites[p.name].position, b = sites[q.name].position;
        EXPECT_LT((Vec3(-a.x(), a.y(), a.z()) - b).norm(), 2.0)
            << set.name << " " << p.name << " / " << q.name;
      }
    }
  }
  EXPECT_EQ(placed, 44 + 41 + 37 + 41);
  EXPECT_GT(faced, 40);
  std::printf("placed %d markers; farthest from its bone: %s, %.0f mm\n", placed, farthest_name.c_str(),
              farthest);
}

// The project's dense layout on the template: every marker named by the dense set, and each on
// a triangle of its region.
TEST(MarkerSetFile, DenseLayoutMarkersLieInTheirRegions) {
  const Template& t = makehuman();
  const Anatomy anatomy = Anatomy::from(t.body);
  const std::vector<synth::MarkerSite> layout =
      synth::layout_markers(t.body.rest, t.triangles, t.body.weights, t.body.skeleton, anatomy, {}, 7);
  ASSERT_EQ(layout.size(), 350u);
  std::vector<std::string> labels;
  for (const auto& m : layout) labels.push_back("Synth:" + m.name);
  const MarkerSetMatch match = match_marker_set(shipped(), labels);
  ASSERT_EQ(match.set, set_index(kDense));
  EXPECT_EQ(match.matched, 350);
  const MarkerSet& dense = shipped()[static_cast<size_t>(match.set)];
  std::vector<std::vector<char>> regions;
  for (const MarkerPlacement& p : dense.markers) regions.push_back(region_triangles(t.body, t.triangles, p));
  std::vector<int> used(dense.markers.size(), 0);
  for (size_t i = 0; i < layout.size(); ++i) {
    const int entry = match.placement[i];
    ASSERT_GE(entry, 0) << layout[i].name;
    ++used[static_cast<size_t>(entry)];
    EXPECT_TRUE(regions[static_cast<size_t>(entry)][static_cast<size_t>(layout[i].triangle)])
        << layout[i].name << " on triangle " << layout[i].triangle << " outside "
        << dense.markers[static_cast<size_t>(entry)].pattern;
  }
  for (size_t e = 0; e < used.size(); ++e)
    EXPECT_GT(used[e], 0) << dense.markers[e].pattern << " names no marker";
  // Regions restrict: none covers most of the body.
  for (size_t e = 0; e < regions.size(); ++e) {
    const double share =
        static_cast<double>(std::count(regions[e].begin(), regions[e].end(), 1)) / regions[e].size();
    EXPECT_LT(share, 0.25) << dense.markers[e].pattern;
  }
}

// ---- Real captures ----

std::vector<std::string> capture_labels(const std::string& relative) {
  return read_capture(test::shared_path("data/captures/" + relative)).labels;
}

TEST(MarkerSetFile, RealCapturesNameTheirSets) {
  struct Case {
    std::string capture, set;
    int matched, labelled;
  };
  const std::vector<Case> known = {
      {"cmu/85_02.c3d", kCmu, 41, 41},
      {"cmu/85_12.c3d", kCmu, 41, 41},
      {"hdm05/HDM_bd_05-01_01_120.c3d", kCmu, 41, 41},  // and three unlabelled points
      {"hdm05/HDM_dg_06-03_03_120.c3d", kCmu, 41, 41},
      {"kineticstoolkit/kinematics_tennis_serve.c3d", kPlugInGait, 39, 39},
  };
  for (const Case& c : known) {
    const std::vector<std::string> labels = capture_labels(c.capture);
    const MarkerSetMatch m = match_marker_set(shipped(), labels);
    ASSERT_EQ(m.set, set_index(c.set)) << c.capture;
    EXPECT_EQ(m.matched, c.matched) << c.capture;
    EXPECT_EQ(m.labelled, c.labelled) << c.capture;
    EXPECT_TRUE(m.known()) << c.capture;
    // Each label to the entry of its own bare name (or, for RBAK, the alias).
    for (size_t l = 0; l < labels.size(); ++l) {
      if (m.placement[l] < 0) continue;
      const MarkerPlacement& p =
          shipped()[static_cast<size_t>(m.set)].markers[static_cast<size_t>(m.placement[l])];
      const std::string bare = bare_label(labels[l]);
      EXPECT_TRUE(p.name == bare || std::find(p.aliases.begin(), p.aliases.end(), bare) != p.aliases.end())
          << c.capture << ": " << labels[l] << " -> " << p.name;
    }
    std::printf("%s: %s\n", c.capture.c_str(), describe_match(shipped(), labels, m).c_str());
  }
  // Other labs' sets: a few coincident names, no known set.
  for (const char* capture : {"c3d-org/sample01/Eb015pi.c3d", "c3d-org/sample02/pc_real.c3d",
                              "c3d-org/Sample_Jump2.c3d", "kineticstoolkit/kinematics_basket_sprint.c3d"}) {
    const std::vector<std::string> labels = capture_labels(capture);
    const MarkerSetMatch m = match_marker_set(shipped(), labels);
    EXPECT_FALSE(m.known()) << capture;
    const std::string line = describe_match(shipped(), labels, m);
    EXPECT_EQ(line.rfind("no known marker set", 0), 0u) << line;
    std::printf("%s: %s\n", capture, line.c_str());
  }
  const MarkerSetMatch sample01 = match_marker_set(shipped(), capture_labels("c3d-org/sample01/Eb015pi.c3d"));
  EXPECT_LE(sample01.matched, 2);
}

// Each shipped set names its own markers whatever the vendor's prefix, and no other set names
// as many of them.
TEST(MarkerSetFile, EachSetNamesItsOwnMarkersBehindAnyPrefix) {
  for (size_t s = 0; s < shipped().size(); ++s) {
    if (shipped()[s].name == kDense) continue;
    for (const char* prefix : {"", "Actor7:", "Q_", "Karlie_", "Skeleton 002_"}) {
      std::vector<std::string> labels;
      for (const MarkerPlacement& p : shipped()[s].markers) labels.push_back(prefix + p.name);
      const MarkerSetMatch m = match_marker_set(shipped(), labels);
      EXPECT_EQ(m.set, static_cast<int>(s)) << shipped()[s].name << " behind '" << prefix << "'";
      EXPECT_EQ(m.matched, static_cast<int>(labels.size()))
          << shipped()[s].name << " behind '" << prefix << "'";
    }
  }
}

// A real actor's markers in the first frame of a take beside the named markers' sites on the
// template, both by marker name; the sites lifted off the skin as a marker is (about 7 mm of
// ball radius and 3 mm of base) and the template scaled to the actor's head-to-heel marker height.
struct ActorAndTemplate {
  std::map<std::string, Vec3> actor, model;
  double scale = 1.0;
};

ActorAndTemplate first_frame_against_template(const std::string& capture_path, const std::string& set_name) {
  const Template& t = makehuman();
  const Capture capture = read_capture(test::shared_path("data/captures/" + capture_path));
  const MarkerSetMatch m = match_marker_set(shipped(), capture.labels);
  EXPECT_EQ(m.set, set_index(set_name)) << capture_path;
  const MarkerSet& set = shipped()[static_cast<size_t>(m.set)];
  const double marker_height_mm = 10.0;
  ActorAndTemplate out;
  for (int l = 0; l < capture.point_count(); ++l) {
    if (m.placement[static_cast<size_t>(l)] < 0 || !capture.present(0, l)) continue;
    const MarkerPlacement& p = set.markers[static_cast<size_t>(m.placement[static_cast<size_t>(l)])];
    out.actor[p.name] = capture.at(0, l);
    const SurfacePoint s = place_marker(t.body, t.triangles, t.bvh, p);
    out.model[p.name] = s.position + marker_height_mm * s.normal;
  }
  auto height = [](std::map<std::string, Vec3>& x) {
    return 0.25 * (x["LFHD"] + x["RFHD"] + x["LBHD"] + x["RBHD"]).z() - 0.5 * (x["LHEE"] + x["RHEE"]).z();
  };
  out.scale = height(out.actor) / height(out.model);
  std::printf("%s: head-to-heel marker height: actor %.0f mm, template %.0f mm, scale %.3f\n",
              capture_path.c_str(), height(out.actor), height(out.model), out.scale);
  return out;
}

// The Plug-in Gait sites against a real standing actor: the first frame of the tennis serve
// (a standing pose). Distances between markers of one rigid segment do not depend on the pose.
TEST(MarkerSetFile, PlugInGaitSegmentWidthsAgreeWithTheTennisServe) {
  ActorAndTemplate x =
      first_frame_against_template("kineticstoolkit/kinematics_tennis_serve.c3d", kPlugInGait);
  ASSERT_EQ(x.actor.size(), 39u);  // every marker present in the first frame
  EXPECT_GT(x.scale, 0.8);
  EXPECT_LT(x.scale, 1.25);
  const std::vector<std::pair<const char*, const char*>> pairs = {
      {"LASI", "RASI"}, {"LPSI", "RPSI"}, {"LASI", "LPSI"}, {"RASI", "RPSI"}, {"LSHO", "RSHO"},
      {"LFHD", "RFHD"}, {"LBHD", "RBHD"}, {"LFHD", "LBHD"}, {"RFHD", "RBHD"}, {"CLAV", "STRN"},
      {"C7", "T10"},    {"C7", "CLAV"},   {"LKNE", "LANK"}, {"RKNE", "RANK"}, {"LHEE", "LTOE"},
      {"RHEE", "RTOE"}, {"LWRA", "LWRB"}, {"RWRA", "RWRB"}};
  std::vector<double> ratios;
  for (const auto& [a, b] : pairs) {
    const double real = (x.actor[a] - x.actor[b]).norm(), ours = x.scale * (x.model[a] - x.model[b]).norm();
    ratios.push_back(ours / real);
    std::printf("  %-4s-%-4s actor %5.0f mm  template %5.0f mm  ratio %.2f\n", a, b, real, ours, ours / real);
  }
  std::vector<double> sorted = ratios;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::printf("  median ratio %.2f, range %.2f..%.2f\n", median, sorted.front(), sorted.back());
  // What is robust: the typical segment width within 15% of the actor's, none off by a third.
  // The wrist markers stand on a bar about 2 cm off the skin on either side: the sites on the
  // skin are closer together than they are, never farther.
  EXPECT_GT(median, 0.85);
  EXPECT_LT(median, 1.15);
  for (size_t i = 0; i < pairs.size(); ++i) {
    const bool bar = std::string(pairs[i].first).find("WR") != std::string::npos;
    EXPECT_GT(ratios[i], bar ? 0.4 : 0.7) << pairs[i].first << "-" << pairs[i].second;
    EXPECT_LT(ratios[i], bar ? 1.0 : 1.3) << pairs[i].first << "-" << pairs[i].second;
  }
}

// Where the trunk, pelvis and head sites sit against real actors' markers after the best rigid
// fit of the scaled template (limbs left out: their pose differs), in the first frame of each
// take. A marker on the wrong side or segment would be 15 cm or more away; posture (the actors
// are not in the template's upright A-pose) and the actor's shape leave a few centimetres: the
// medians are 34 to 70 mm.
TEST(MarkerSetFile, TrunkSitesFitRealActorsWithinCentimetres) {
  const std::vector<std::string> pig = {"C7",   "T10",  "CLAV", "STRN", "RBAK", "LASI", "RASI", "LPSI",
                                        "RPSI", "LFHD", "RFHD", "LBHD", "RBHD", "LSHO", "RSHO"};
  const std::vector<std::string> cmu = {"C7",   "T10",  "CLAV", "STRN", "RBAC", "LFWT", "RFWT", "LBWT",
                                        "RBWT", "LFHD", "RFHD", "LBHD", "RBHD", "LSHO", "RSHO"};
  struct Take {
    std::string capture, set;
    const std::vector<std::string>& trunk;
  };
  const std::vector<Take> takes = {{"kineticstoolkit/kinematics_tennis_serve.c3d", kPlugInGait, pig},
                                   {"cmu/85_02.c3d", kCmu, cmu},
                                   {"cmu/85_12.c3d", kCmu, cmu},
                                   {"hdm05/HDM_bd_05-01_01_120.c3d", kCmu, cmu},
                                   {"hdm05/HDM_dg_06-03_03_120.c3d", kCmu, cmu}};
  for (const Take& take : takes) {
    ActorAndTemplate x = first_frame_against_template(take.capture, take.set);
    std::vector<Vec3> from, to;
    for (const std::string& n : take.trunk) {
      ASSERT_TRUE(x.actor.count(n)) << take.capture << " " << n;
      from.push_back(x.scale * x.model[n]);
      to.push_back(x.actor[n]);
    }
    RigidTransform fit;
    fit_rigid(from, to, fit);
    std::vector<double> residuals;
    std::printf("  after a rigid fit (mm):");
    for (size_t i = 0; i < take.trunk.size(); ++i) {
      residuals.push_back((fit.apply(from[i]) - to[i]).norm());
      std::printf(" %s %.0f", take.trunk[i].c_str(), residuals.back());
    }
    std::sort(residuals.begin(), residuals.end());
    std::printf("\n  median %.0f mm, max %.0f mm\n", residuals[residuals.size() / 2], residuals.back());
    EXPECT_LT(residuals[residuals.size() / 2], 80.0) << take.capture;
    EXPECT_LT(residuals.back(), 120.0) << take.capture;
  }
}

// ---- Pictures to look at ----

struct Projector {
  render::Camera camera;
  Vec3 right, up, forward;
  double scale;
  explicit Projector(const render::Camera& c) : camera(c) {
    forward = (c.target - c.eye).normalized();
    right = forward.cross(c.up).normalized();
    up = right.cross(forward);
    scale = 0.5 * c.height /
            ((c.target - c.eye).norm() * std::tan(c.vertical_fov_degrees * std::numbers::pi / 360.0));
  }
  std::pair<int, int> pixel(const Vec3& p) const {
    const Vec3 d = p - camera.eye;
    return {static_cast<int>(0.5 * camera.width + scale * d.dot(right)),
            static_cast<int>(0.5 * camera.height - scale * d.dot(up))};
  }
};

void dot(render::Image& image, int x, int y, render::Rgb colour) {
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx)
      if (dx * dx + dy * dy <= 10 && x + dx >= 0 && y + dy >= 0 && x + dx < image.width &&
          y + dy < image.height)
        image.set(x + dx, y + dy, colour);
}

constexpr int kViewWidth = 480, kViewHeight = 660;

// Front and back of the template with each set's markers (left red, right blue, midline green;
// names beside them), written to the scratch folder for a person to look at.
TEST(MarkerSetFile, RendersEachSet) {
  const Template& t = makehuman();
  for (const MarkerSet& set : shipped()) {
    if (set.name == kDense) continue;
    std::vector<render::Image> views;
    for (const render::View view : {render::View::front, render::View::back}) {
      const render::Camera camera = render::frame_view(t.body.rest, view, kViewWidth, kViewHeight,
                                                       render::Projection::orthographic, 30.0, 1.05);
      render::Image image = render::render_mesh(render::RenderMesh(t.body.rest, t.triangles), camera);
      const Projector project(camera);
      int drawn = 0;
      for (const MarkerPlacement& p : set.markers) {
        const SurfacePoint s = place_marker(t.body, t.triangles, t.bvh, p);
        // Hidden when the body stands between the marker (a little above the skin) and the camera.
        const Vec3 lifted = s.position + 8.0 * s.normal;
        if (t.bvh.segment_blocked(lifted, lifted - 3000.0 * project.forward, 1.0)) continue;
        const auto [x, y] = project.pixel(s.position);
        const int side = named_side(p.name);
        dot(image, x, y,
            side < 0   ? render::Rgb{220, 0, 0}
            : side > 0 ? render::Rgb{0, 60, 230}
                       : render::Rgb{0, 150, 0});
        // The name beside the dot, away from the body's midline.
        const int text_x = x < image.width / 2 - 8 ? x - 5 - render::text_width(p.name, 1) : x + 5;
        render::draw_text(image, text_x, y - 3, p.name, {0, 0, 0}, 1);
        ++drawn;
      }
      EXPECT_GT(drawn, 10) << set.name;
      views.push_back(std::move(image));
    }
    const std::vector<std::string> captions = {set.name + ", front", "back"};
    std::string file = set.name;
    for (char& c : file)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    const std::string path = test::scratch_path("marker_set_" + file + ".png");
    write_png(path, render::compose_side_by_side(views, captions));
    const render::Image back = read_png(path);
    EXPECT_EQ(back.width, 2 * kViewWidth + 8);
    std::printf("%s\n", path.c_str());
  }
}

}  // namespace
}  // namespace skinstream
