// `skinstream build-subject` with the body template and `skinstream eval-actor`, run as a user
// would on real captures: a real actor's subject is fitted, checked and written; what is not a
// body, or not an actor, is refused in one line with nothing written.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "core/body/anatomy.h"
#include "core/body/skinning.h"
#include "core/fitting/body_proportions.h"
#include "core/fitting/template_segments.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/makehuman.h"
#include "support/cli_run.h"
#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::ProgramRun;
using test::run_cli;

const std::string kTemplate = test::source_path("replay_data/makehuman/makehuman_hm08_body_only.obj");
using test::kCmu02;
const std::string kTennis = test::shared_path("data/captures/kineticstoolkit/kinematics_tennis_serve.c3d");

// A refusal: a non-zero exit, one line that says `why`, and no subject file.
void expect_refused(const ProgramRun& r, const std::string& out_path, const std::string& why) {
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_path)) << out_path;
}

// A triangulated sphere (a "mesh that is not a body"), radius 900 mm.
TriangleMesh sphere(int rings, int segments) {
  TriangleMesh m;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = M_PI * r / rings, phi = 2 * M_PI * s / segments;
      m.vertices.push_back(900.0 * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)) +
                           Vec3(0, 0, 900));
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int a = r * segments + s, b = r * segments + (s + 1) % segments;
      m.faces.push_back({a, a + segments, b + segments});
      m.faces.push_back({a, b + segments, b});
    }
  return m;
}

TEST(SkinstreamActor, BuildsARealActorFromTheTemplateAndSaysWhatItMeasured) {
  const std::string subject = test::scratch_path("cmu02_actor.sksubj");
  const ProgramRun r = run_cli("build-subject --capture " + kCmu02 + " --mesh " + kTemplate + " --out " + subject, false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(r.output);
  const nlohmann::json& actor = report["actor"];
  EXPECT_EQ(actor["marker_set"], "CMU / HDM05 41-marker set");
  EXPECT_FALSE(actor["blind_start"].get<bool>());
  EXPECT_TRUE(actor["checks"]["plausible"].get<bool>());
  // The registration moves the skin onto the markers without folding it: a handful of triangles
  // where the template nearly touches itself, at most (the check's own limit: 5 of 26,756).
  EXPECT_LE(actor["checks"]["registration"]["flipped_triangles"].get<int>(), 5);
  EXPECT_LT(report["mesh"]["landmark_rms_after_mm"].get<double>(), 2.0);
  // A human's proportions: the height of an adult, every segment within its range.
  EXPECT_GT(actor["height_mm"].get<double>(), 1500.0);
  EXPECT_LT(actor["height_mm"].get<double>(), 2000.0);
  EXPECT_EQ(actor["segment_lengths"].size(), 10u);
  // Parts by the skeleton for a sparse set, each with the terms its markers carry and why.
  EXPECT_EQ(actor["parts"].size(), 18u);
  for (const auto& part : actor["parts"]) EXPECT_FALSE(part["terms"].get<std::string>().empty());
  // The file holds the fitted body: the daemon poses it by its skeleton.
  const SubjectFile file = read_subject_file(subject);
  ASSERT_TRUE(file.deformation.has_value());
  EXPECT_EQ(file.deformation->skeleton.segment_count(), 18);
  EXPECT_EQ(file.deformation->rest_vertices.size(), file.deformation->reference_vertices.size());
}

TEST(SkinstreamActor, ASphereIsNotABody) {
  const std::string mesh = test::scratch_path("sphere.ply");
  write_ply(mesh, sphere(24, 48));
  const std::string out = test::scratch_path("sphere.sksubj");
  expect_refused(run_cli("build-subject --capture " + kCmu02 + " --mesh " + mesh + " --out " + out), out, "not a body");
}

TEST(SkinstreamActor, AWrongUnitFlagIsRefused) {
  const std::string out = test::scratch_path("wrong_unit.sksubj");
  // The template is in decimetres: in metres it would be 16.7 m tall.
  expect_refused(run_cli("build-subject --capture " + kCmu02 + " --mesh " + kTemplate + " --mesh-unit m --out " + out), out, "tall");
}

// Markers that wander about a room on their own: no body can carry them.
TEST(SkinstreamActor, MarkersThatNoBodyCarriesAreRefused) {
  std::vector<std::string> labels;
  for (int i = 0; i < 30; ++i) labels.push_back("point" + std::to_string(i));
  Capture cloud(labels, 600, 120.0);
  for (int i = 0; i < 30; ++i) {
    Vec3 p(37.0 * i - 500.0, 500.0 - 29.0 * i, 100.0 + 60.0 * i);
    for (int f = 0; f < 600; ++f) {
      p += Vec3(std::sin(0.05 * f + i), std::cos(0.07 * f + 2 * i), std::sin(0.03 * f - i)) * 6.0;
      cloud.at(f, i) = p;
    }
  }
  const std::string capture = test::scratch_path("cloud.c3d");
  write_capture(cloud, capture);
  const std::string out = test::scratch_path("cloud.sksubj");
  expect_refused(run_cli("build-subject --capture " + capture + " --mesh " + kTemplate + " --out " + out), out,
                 "cannot be placed on a body");
}

// Markers on a tumbling box move as one rigid thing, which a body's pelvis alone can follow;
// the body that would carry them is no human's.
TEST(SkinstreamActor, MarkersOnABoxAreRefused) {
  std::vector<std::string> labels;
  std::vector<Vec3> corners;
  for (int i = 0; i < 24; ++i) {
    labels.push_back("box" + std::to_string(i));
    corners.push_back(Vec3((i & 1 ? 200 : -200) + 10 * (i % 5), (i & 2 ? 150 : -150) + 7 * (i % 3), (i & 4 ? 300 : -300) + 5 * i));
  }
  Capture box(labels, 600, 120.0);
  for (int f = 0; f < 600; ++f) {
    const Eigen::Matrix3d turn =
        (Eigen::AngleAxisd(0.02 * f, Vec3::UnitZ()) * Eigen::AngleAxisd(0.013 * f, Vec3::UnitX())).toRotationMatrix();
    for (int i = 0; i < 24; ++i) box.at(f, i) = turn * corners[i] + Vec3(0, 0, 1000);
  }
  const std::string capture = test::scratch_path("box.c3d");
  write_capture(box, capture);
  const std::string out = test::scratch_path("box.sksubj");
  expect_refused(run_cli("build-subject --capture " + capture + " --mesh " + kTemplate + " --out " + out), out, "rigid object");
}

// A calibration take of an actor standing still (one real frame held for two seconds, 1 mm of
// marker noise): no joint moves, so none can be fitted; refused before the fit.
TEST(SkinstreamActor, AnActorStandingStillIsRefused) {
  const Capture take = read_capture(kCmu02);
  Capture still(take.labels, 240, take.rate_hz);
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int f = 0; f < still.frame_count; ++f)
    for (int i = 0; i < take.point_count(); ++i) still.at(f, i) = take.at(100, i) + Vec3(noise(random), noise(random), noise(random));
  const std::string capture = test::scratch_path("still.c3d");
  write_capture(still, capture);
  const std::string out = test::scratch_path("still.sksubj");
  expect_refused(run_cli("build-subject --capture " + capture + " --mesh " + kTemplate + " --out " + out), out, "standing still");
}

TEST(SkinstreamActor, ATakeWithNoCompleteFrameIsRefused) {
  Capture take = read_capture(kCmu02);
  for (int f = 0; f < take.frame_count; ++f) take.at(f, f % take.point_count()) = missing_point();
  const std::string capture = test::scratch_path("never_complete.c3d");
  write_capture(take, capture);
  const std::string out = test::scratch_path("never_complete.sksubj");
  expect_refused(run_cli("build-subject --capture " + capture + " --mesh " + kTemplate + " --out " + out), out,
                 "all 41 labelled markers");
}

// A scan of someone else, as a scanner hands it over: the MakeHuman body with other proportions,
// standing with its arms up in a T, in centimetres with Y up, its vertices shuffled, no skeleton.
TEST(SkinstreamActor, AScanInItsOwnPoseUnitAndAxesGoesThroughTheTemplate) {
  const Body body = load_makehuman(test::source_path("replay_data/makehuman"));
  const TemplateSegments segments = segment_template(body.skeleton);
  BodyProportions proportions = BodyProportions::neutral(segments);
  proportions.overall = 1.05;
  proportions.girth[1] = 1.1;  // the abdomen
  const std::vector<Vec3> rest = proportioned_vertices(body.rest, body.weights, proportion_bones(body.skeleton, segments, proportions));
  const Anatomy anatomy = Anatomy::from(body);
  PoseBuilder pose(body.skeleton, anatomy);
  pose.shoulder(kLeft, 0.0, 90.0);
  pose.shoulder(kRight, 0.0, 90.0);
  const std::vector<Vec3> posed = skin(rest, body.weights, pose_bones(body.skeleton, pose.pose()));
  std::vector<int> order(posed.size()), where(posed.size());
  for (size_t v = 0; v < order.size(); ++v) order[v] = static_cast<int>((v * 7919) % order.size());  // 7919 is prime: a permutation
  for (size_t k = 0; k < order.size(); ++k) where[static_cast<size_t>(order[k])] = static_cast<int>(k);
  TriangleMesh scan;
  for (int v : order) {
    const Vec3& p = posed[static_cast<size_t>(v)];
    scan.vertices.push_back(Vec3(-p.x(), p.z(), p.y()) / 10.0);  // skinstream axes to centimetres, Y up, facing +Z
  }
  for (const Triangle& t : triangulate(body.faces)) scan.faces.push_back({where[t[0]], where[t[1]], where[t[2]]});
  const std::string mesh = test::scratch_path("scan_cm_yup.ply");
  write_ply(mesh, scan);

  const std::string subject = test::scratch_path("scan_actor.sksubj");
  const ProgramRun r = run_cli("build-subject --capture " + kCmu02 + " --mesh " + mesh + " --out " + subject, false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(r.output);
  const nlohmann::json& through = report["mesh"]["through_the_template"];
  EXPECT_EQ(through["unit_mm"], 10.0);
  EXPECT_GT(through["arm_elevation_deg"].get<double>(), 75.0);  // a T pose
  EXPECT_LT(through["scan_to_template_median_mm"].get<double>(), 3.0);
  // The template fitted from the scan's raised arms, not pulled into its trunk (1.5 mm; from the
  // A pose alone 5.4 mm, a forearm turned 81 degrees and the take's wrist torn to 24 typical edges).
  EXPECT_LT(through["template_fit_rms_mm"].get<double>(), 3.0);
  const nlohmann::json& checks = report["actor"]["checks"];
  EXPECT_TRUE(checks["plausible"].get<bool>());
  // Far from the stretch limit, as the template itself is on this take (11.5 of 25).
  EXPECT_LT(checks["take_longest_stretched_edge"]["typical_edges"].get<double>(),
            0.7 * checks["take_longest_stretched_edge"]["limit"].get<double>());
  // The subject's body is the scan: its vertices, in its order.
  const SubjectFile file = read_subject_file(subject);
  ASSERT_TRUE(file.deformation.has_value());
  EXPECT_EQ(file.deformation->vertex_count(), static_cast<int>(scan.vertices.size()));
  EXPECT_EQ(file.deformation->faces, scan.faces);
}

// The measure on a real take: withheld markers followed through the second half, three methods.
TEST(SkinstreamActor, EvalActorMeasuresHeldOutMarkersOnARealTake) {
  const ProgramRun r = run_cli("eval-actor --capture " + kTennis + " --folds 2 --stride 4 --json", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(r.output);
  EXPECT_EQ(report["marker_set"], "Vicon Plug-in Gait (full body)");
  ASSERT_EQ(report["rows"].size(), 3u);
  EXPECT_EQ(report["rows"][0]["method"], "full method");
  EXPECT_EQ(report["rows"][1]["method"], "template LBS");
  EXPECT_EQ(report["rows"][2]["method"], "rigid parts");
  EXPECT_EQ(report["fold_reports"].size(), 2u);
  for (const auto& row : report["rows"]) {
    EXPECT_GT(row["samples"].get<int>(), 100);
    EXPECT_EQ(row["per_marker"].size(), 10u);  // two folds of five
  }
  // Rigid parts lose the segments with fewer than three markers of their own to their parents:
  // both skinned rows follow the skin far better.
  EXPECT_LT(report["rows"][0]["mean_mm"].get<double>(), 0.5 * report["rows"][2]["mean_mm"].get<double>());
  EXPECT_LT(report["rows"][1]["mean_mm"].get<double>(), 0.5 * report["rows"][2]["mean_mm"].get<double>());
}

}  // namespace
}  // namespace skinstream
