// The MakeHuman loader against the real CC0 files in ../shared/data/meshes/makehuman, and the
// synthetic capture generator driven by that body (spacing, occlusion, non-rigid skin, truth).
#include "protocol/offline/makehuman.h"

#include <gtest/gtest.h>

#include "support/rigid_residual.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <string>

#include "core/body/anatomy.h"
#include "core/geometry/triangle_bvh.h"
#include "core/synth/subdivision.h"
#include "core/synth/synth_capture.h"
#include "protocol/files/file_error.h"
#include "support/test_data.h"

namespace skinstream {
namespace {


std::string mh_dir() { return test::shared_path("data/meshes/makehuman"); }

const Body& body() {
  static const Body b = load_makehuman(mh_dir());
  return b;
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// A copy of the standard file set with one file replaced.
MakeHumanFiles with(const std::string& which, const std::string& replacement) {
  MakeHumanFiles f = MakeHumanFiles::in(mh_dir());
  if (which == "body") f.body_obj = replacement;
  if (which == "base") f.base_obj = replacement;
  if (which == "skeleton") f.skeleton = replacement;
  if (which == "weights") f.weights = replacement;
  return f;
}

void expect_file_error(const MakeHumanFiles& files, const std::string& path, const std::string& words) {
  try {
    load_makehuman(files);
    FAIL() << "no error for " << path;
  } catch (const FileError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(words), std::string::npos) << what;
  }
}

TEST(MakeHumanLoad, MissingAndMalformedFilesAreFileErrors) {
  EXPECT_THROW(load_makehuman(test::scratch_path("no_such_folder")), FileError);
  const std::string bad_face = test::scratch_path("mh_bad_face.obj");
  write_text(bad_face, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  expect_file_error(with("body", bad_face), bad_face, "out of range");
  const std::string no_vertices = test::scratch_path("mh_empty.obj");
  write_text(no_vertices, "# nothing\n");
  expect_file_error(with("body", no_vertices), no_vertices, "no vertices");
  const std::string stray = test::scratch_path("mh_stray_vertex.obj");
  write_text(stray, "v 0.123 45.6 7.89\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");  // not in base.obj
  expect_file_error(with("body", stray), MakeHumanFiles::in(mh_dir()).base_obj, "no vertex at the position");
  const std::string bad_json = test::scratch_path("mh_bad.mhskel");
  write_text(bad_json, "{ \"bones\": ");
  expect_file_error(with("skeleton", bad_json), bad_json, "not valid JSON");
  const std::string bad_joint = test::scratch_path("mh_bad_joint.mhskel");
  write_text(bad_joint,
             R"({"joints": {"a": [0]}, "bones": {"root": {"head": "a", "tail": "zz", "parent": null}}})");
  expect_file_error(with("skeleton", bad_joint), bad_joint, "unknown joint zz");
  const std::string bad_weights = test::scratch_path("mh_bad_weights.mhw");
  write_text(bad_weights, R"({"weights": {"no_such_bone": [[0, 1.0]]}})");
  expect_file_error(with("weights", bad_weights), bad_weights, "unknown bone no_such_bone");
}

TEST(MakeHumanLoad, BodyOnlyVerticesAreTheFirstVerticesOfBaseObj) {
  const ObjMesh part = read_obj(MakeHumanFiles::in(mh_dir()).body_obj);
  const ObjMesh whole = read_obj(MakeHumanFiles::in(mh_dir()).base_obj);
  ASSERT_EQ(part.vertices.size(), 13380u);
  ASSERT_EQ(whole.vertices.size(), 19158u);
  const std::vector<int> map = match_vertices(part.vertices, whole.vertices);
  for (int i = 0; i < 13380; ++i) ASSERT_EQ(map[static_cast<size_t>(i)], i);
  // A vertex that is nowhere in the whole mesh has no match; a shifted copy finds its twin.
  std::vector<Vec3> probe = {Vec3(100, 100, 100), whole.vertices[15000] + Vec3(2e-5, 0, 0)};
  const std::vector<int> m = match_vertices(probe, whole.vertices);
  EXPECT_EQ(m[0], -1);
  EXPECT_EQ(m[1], 15000);
}

TEST(MakeHumanLoad, BodySkeletonAndWeightsInMillimetresZUp) {
  const Body& b = body();
  EXPECT_EQ(b.vertex_count(), 13380);
  EXPECT_EQ(b.faces.size(), 13378u);
  for (const auto& f : b.faces) ASSERT_GE(f[3], 0);  // all quads
  EXPECT_EQ(b.skeleton.size(), 163);
  EXPECT_EQ(b.weights.vertex_count(), 13380);
  for (int v = 0; v < b.vertex_count(); v += 7) {
    double sum = 0.0;
    for (int k = b.weights.begin(v); k < b.weights.end(v); ++k)
      sum += b.weights.weights[static_cast<size_t>(k)];
    ASSERT_NEAR(sum, 1.0, 1e-12);
  }
  Vec3 lo = Vec3::Constant(1e18), hi = -lo;
  for (const Vec3& p : b.rest) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  EXPECT_NEAR(lo.z(), 0.0, 1e-9);          // soles on the floor
  EXPECT_NEAR(hi.z(), 1666.0, 5.0);        // 16.66 MakeHuman decimetres tall
  EXPECT_NEAR(lo.x() + hi.x(), 0.0, 1.0);  // symmetric about x = 0
  EXPECT_GT(signed_volume(b.rest, triangulate(b.faces)), 0.04e9);  // outward, ~60 litres
  const Skeleton& sk = b.skeleton;
  EXPECT_LT(sk.bone(sk.require("upperarm01.L")).head.x(), -100.0);  // left on -X
  EXPECT_GT(sk.bone(sk.require("upperarm01.R")).head.x(), 100.0);
  const Vec3 toe = sk.bone(sk.require("toe1-1.L")).head, ankle = sk.bone(sk.require("foot.L")).head;
  EXPECT_GT(toe.y(), ankle.y() + 80.0);  // toes point forward (+Y)
  const Vec3 hips =
      0.5 * (sk.bone(sk.require("upperleg01.L")).head + sk.bone(sk.require("upperleg01.R")).head);
  EXPECT_LT(hips.head<2>().norm(), 1e-9);  // hip centre above the origin
  EXPECT_GT(sk.bone(sk.require("head")).tail.z(), 1550.0);
  // Vertices follow their bones: the dominant bone of the left hand's vertices is a hand bone.
  int hand = 0;
  for (int v = 0; v < b.vertex_count(); ++v)
    if (b.rest[static_cast<size_t>(v)].x() < -400.0)
      hand += sk.is_descendant(b.weights.dominant(v), sk.require("wrist.L")) ||
              sk.is_descendant(b.weights.dominant(v), sk.require("lowerarm02.L"));
  EXPECT_GT(hand, 100);
}

TEST(MakeHumanLoad, SubdividesToAbout53000Vertices) {
  const Body fine = synth::subdivide(body());
  EXPECT_GT(fine.vertex_count(), 53000);
  EXPECT_LT(fine.vertex_count(), 54000);
  EXPECT_EQ(fine.faces.size(), 4 * body().faces.size());
}

// --- The generator on the MakeHuman body -------------------------------------------------------

using test::rigid_residual;

std::vector<int> region(const synth::SynthCapture& c, const std::string& name) {
  std::vector<int> out;
  for (int i = 0; i < c.truth.point_count(); ++i)
    if (c.markers[static_cast<size_t>(i)].region == name) out.push_back(i);
  return out;
}

double missing_fraction(const synth::SynthCapture& c, const std::vector<int>& markers) {
  const int n = c.truth.point_count();
  long missing = 0;
  for (int f = 0; f < c.frame_count(); ++f)
    for (int i : markers) missing += !c.visible[static_cast<size_t>(f) * n + i];
  return static_cast<double>(missing) / (static_cast<double>(markers.size()) * c.frame_count());
}

TEST(MakeHumanSynth, ThreeHundredFiftyMarkersFourToFiveCentimetresApart) {
  for (uint64_t seed : {1u, 2u}) {
    synth::SynthOptions o;
    o.motion = "static";
    o.seconds = 0.05;
    o.seed = seed;
    const synth::SynthCapture c = synth::generate(body(), o);
    ASSERT_EQ(c.truth.point_count(), 350);
    std::vector<double> nearest;
    for (int i = 0; i < 350; ++i) {
      double best = 1e18;
      for (int j = 0; j < 350; ++j)
        if (i != j) best = std::min(best, (c.truth.at(0, i) - c.truth.at(0, j)).norm());
      nearest.push_back(best);
    }
    std::sort(nearest.begin(), nearest.end());
    EXPECT_GT(nearest[175], 40.0) << "seed " << seed;
    EXPECT_LT(nearest[175], 50.0) << "seed " << seed;
    EXPECT_GT(nearest.front(), 10.0);
    for (const char* name :
         {"abdomen_1", "chest_1", "upperback_1", "thigh_L_1", "thigh_R_1", "elbow_L_1", "elbow_R_3",
          "scapula_L_1", "scapula_R_2", "upperarm_L_1", "forearm_R_1", "calf_L_1"})
      EXPECT_GE(c.truth.label_index(name), 0) << name;
  }
}

TEST(MakeHumanSynth, ArmpitsAndCrouchedBellyGoMissingMoreThanTheChest) {
  synth::SynthOptions o;
  o.motion = "rom";
  o.seconds = 10.0;
  const synth::SynthCapture c = synth::generate(body(), o);
  const Anatomy a = Anatomy::from(body());
  std::vector<int> armpit, chest;
  for (int i = 0; i < c.truth.point_count(); ++i) {
    const synth::MarkerSite& m = c.markers[static_cast<size_t>(i)];
    for (Side s : {kLeft, kRight})
      if ((m.rest_position - (a.shoulder_joint[s] - Vec3(0, 0, 70))).norm() < 60.0) armpit.push_back(i);
    if (m.region == "chest" && m.rest_normal.y() > 0.7) chest.push_back(i);
  }
  ASSERT_GE(armpit.size(), 3u);
  ASSERT_GE(chest.size(), 8u);
  const double armpit_missing = missing_fraction(c, armpit), chest_missing = missing_fraction(c, chest);
  EXPECT_GT(armpit_missing, 2.0 * chest_missing);
  EXPECT_GT(armpit_missing, chest_missing + 0.1);
  // In the deep crouch (17.3 s of the 20 s script) most of the belly is hidden.
  const int crouch = static_cast<int>(17.3 / 20.0 * o.seconds * 120.0);
  const std::vector<int> abdomen = region(c, "abdomen");
  int hidden = 0;
  for (int i : abdomen) hidden += !c.visible[static_cast<size_t>(crouch) * 350 + i];
  EXPECT_GT(hidden, static_cast<int>(abdomen.size()) / 2);
  // Overall, like Park & Hodgins' captures: some missing, not most.
  EXPECT_GT(c.counts.occluded_fraction, 0.04);
  EXPECT_LT(c.counts.occluded_fraction, 0.2);
}

TEST(MakeHumanSynth, BreathingAndFlexingAreNotExplainedBySkinning) {
  for (const char* motion : {"breathe", "flex"}) {
    synth::SynthOptions o;
    o.motion = motion;
    o.seconds = 4.0;
    const synth::SynthCapture deformed = synth::generate(body(), o);
    o.deform = false;
    const synth::SynthCapture skinned = synth::generate(body(), o);
    ASSERT_EQ(deformed.truth.labels, skinned.truth.labels);  // same markers
    // Per frame, the best rigid motion of a part's markers from their skinned positions to
    // their true ones leaves this much unexplained (RMS over the frames given).
    auto residual = [&](const std::vector<int>& part, int first, int last) {
      double sum = 0.0;
      for (int f = first; f < last; ++f) {
        std::vector<Vec3> a, b;
        for (int i : part) a.push_back(skinned.truth.at(f, i)), b.push_back(deformed.truth.at(f, i));
        const double r = rigid_residual(a, b);
        sum += r * r;
      }
      return std::sqrt(sum / (last - first));
    };
    if (std::string(motion) == "breathe") {
      // Around full inhalation (2-3 s of the 5 s breath) the belly is well out of rigid.
      EXPECT_GT(residual(region(deformed, "abdomen"), 240, 360), 3.0);
      EXPECT_GT(residual(region(deformed, "chest"), 240, 360), 1.5);
    } else {
      // Holding the double-biceps pose (1.5-3.5 s): the upper arms bulge.
      EXPECT_GT(residual(region(deformed, "upperarm_L"), 180, 420), 3.0);
      EXPECT_GT(residual(region(deformed, "upperarm_R"), 180, 420), 3.0);
      EXPECT_GT(residual(region(deformed, "abdomen"), 0, deformed.frame_count()), 3.0);
    }
    EXPECT_LT(residual(region(deformed, "calf_L"), 0, deformed.frame_count()), 3.0);  // little happens there
  }
}

TEST(MakeHumanSynth, TruthMarkersLieOnTheSubdividedTruthMesh) {
  synth::SynthOptions o;
  o.motion = "punch";
  o.seconds = 1.5;
  o.subdivided = true;
  o.marker_offset_mm = 4.0;
  const synth::SynthCapture c = synth::generate(body(), o);
  EXPECT_GT(c.mesh_vertex_count(), 53000);
  for (int f : {0, 60, 179}) {
    const std::vector<Vec3> mesh = c.pose_mesh(f);
    const TriangleBvh bvh(mesh, c.mesh_triangles());
    int exact = 0;
    for (int i = 0; i < 350; ++i) {
      const synth::MarkerSite& s = c.markers[static_cast<size_t>(i)];
      const Triangle& t = c.mesh_triangles()[static_cast<size_t>(s.triangle)];
      const Vec3 &p0 = mesh[static_cast<size_t>(t[0])], &p1 = mesh[static_cast<size_t>(t[1])],
                 &p2 = mesh[static_cast<size_t>(t[2])];
      const Vec3 foot = s.barycentric[0] * p0 + s.barycentric[1] * p1 + s.barycentric[2] * p2;
      ASSERT_LT((c.truth.at(f, i) - foot - 4.0 * triangle_normal(p0, p1, p2)).norm(), 1e-9);
      const double d = bvh.closest(c.truth.at(f, i));
      ASSERT_LE(d, 4.0 + 1e-9);
      exact += std::abs(d - 4.0) < 0.1;
    }
    // The few others have another part of the body (arm against the side) within 4 mm.
    EXPECT_GE(exact, 0.95 * 350) << "frame " << f;
  }
}

}  // namespace
}  // namespace skinstream
