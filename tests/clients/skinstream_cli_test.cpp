// The real `skinstream` program, run as a user would, on real captures.
#include <gtest/gtest.h>

#include <fstream>
#include <utility>
#include <nlohmann/json.hpp>

#include "core/baselines/linear_interpolation_fill.h"
#include "core/evaluation/fill_error.h"
#include "core/evaluation/gap_plan.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "support/cli_run.h"
#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::ProgramRun;
using test::run_cli;  // `skinstream ARGUMENTS`, stdout and stderr together

// eval-deform on one short breathe take from a 5 s training take: seconds, not minutes.
std::string quick_eval_deform() {
  return "eval-deform --motions breathe --seconds 0.5 --train-seconds 5 --json --body " +
         std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman";
}

// That run with its defaults and with `variant` added, each parsed; null for a run that failed
// (reported as a test failure, with its output).
std::pair<nlohmann::json, nlohmann::json> quick_eval_default_and(const std::string& variant) {
  std::pair<nlohmann::json, nlohmann::json> parsed;
  for (auto [arguments, to] : {std::pair{quick_eval_deform(), &parsed.first},
                               std::pair{quick_eval_deform() + " " + variant, &parsed.second}}) {
    const ProgramRun r = run_cli(arguments);
    if (r.exit_code == 0) *to = nlohmann::json::parse(r.output);
    else ADD_FAILURE() << arguments << ":\n" << r.output;
  }
  return parsed;
}

using test::kCmu02;
using test::kCmu12;

TEST(SkinstreamCli, MissingFileFailsWithOneLineNamingIt) {
  const ProgramRun r = run_cli("info " + test::scratch_path("absent.c3d"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("absent.c3d"), std::string::npos);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(SkinstreamCli, TruncatedCaptureFailsCleanly) {
  std::ifstream in(kCmu02, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = test::scratch_path("cut.c3d");
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  const ProgramRun r = run_cli("info " + cut);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("cut.c3d"), std::string::npos);
}

TEST(SkinstreamCli, UnknownExtensionIsRefused) {
  const ProgramRun r = run_cli("convert " + kCmu02 + " " + test::scratch_path("out.xyz"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("out.xyz"), std::string::npos);
}

TEST(SkinstreamCli, FillRefusesASubjectOfOtherMarkers) {
  const std::string subject = test::scratch_path("cmu.subject");
  ASSERT_EQ(run_cli("build-subject --capture " + kCmu12 + " --out " + subject).exit_code, 0);
  const std::string other = test::scratch_path("other_labels.trc");
  Capture c = read_capture(kCmu02);
  for (auto& l : c.labels) l = "X" + l;
  write_capture(c, other);
  const ProgramRun r = run_cli("fill --subject " + subject + " " + other + " --out " + test::scratch_path("x.c3d"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("none of the subject"), std::string::npos) << r.output;
}

TEST(SkinstreamCli, CorruptSubjectIsRefused) {
  const std::string bad = test::scratch_path("corrupt.subject");
  std::ofstream(bad) << "not a subject";
  const ProgramRun r = run_cli("fill --subject " + bad + " " + kCmu02 + " --out " + test::scratch_path("y.c3d"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("corrupt.subject"), std::string::npos);
}

TEST(SkinstreamCli, InfoReportsTheCapture) {
  const ProgramRun r = run_cli("info --json " + kCmu02);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["frames"], 810);
  EXPECT_EQ(j["labelled_markers"], 41);
  EXPECT_EQ(j["rate_hz"], 120.0);
  EXPECT_EQ(j["missing_fraction"], 0.0);
}

TEST(SkinstreamCli, ConvertsC3dToTrcAndBack) {
  const std::string trc = test::scratch_path("85_02.trc"), back = test::scratch_path("85_02_back.c3d");
  ASSERT_EQ(run_cli("convert " + kCmu02 + " " + trc).exit_code, 0);
  ASSERT_EQ(run_cli("convert " + trc + " " + back).exit_code, 0);
  const Capture a = read_capture(kCmu02), b = read_capture(back);
  ASSERT_EQ(a.labels, b.labels);
  ASSERT_EQ(a.frame_count, b.frame_count);
  double worst = 0;
  for (size_t k = 0; k < a.positions.size(); ++k) worst = std::max(worst, (a.positions[k] - b.positions[k]).norm());
  EXPECT_LT(worst, 1e-3);
}

// End to end on a real capture: train on one take, delete seeded gaps from another, fill it
// with the command-line tool (causal), and compare with the deleted samples.
// Measured (seed 5): mean 16.7 mm, mean normalised 0.065 (linear interpolation: 340 mm).
TEST(SkinstreamCli, FillsDeletedGapsOfARealCaptureAccurately) {
  const std::string subject = test::scratch_path("cmu12.subject");
  ASSERT_EQ(run_cli("build-subject --capture " + kCmu12 + " --out " + subject).exit_code, 0);
  const Capture truth = read_capture(kCmu02);
  GapPlanOptions plan;
  plan.seed = 5;
  const std::vector<Gap> gaps = plan_gaps(truth, plan);
  ASSERT_GT(gaps.size(), 10u);
  const std::string gapped = test::scratch_path("85_02_gaps.c3d"), filled_path = test::scratch_path("85_02_filled.c3d");
  write_capture(apply_gaps(truth, gaps), gapped);
  const ProgramRun r = run_cli("fill --subject " + subject + " " + gapped + " --out " + filled_path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(r.output)["latency_frames"], 0);

  const Capture filled = read_capture(filled_path);
  ASSERT_EQ(filled.labels, truth.labels);
  const SubjectModel model = read_subject(subject);
  std::vector<double> normaliser;
  for (int i = 0; i < model.marker_count(); ++i) normaliser.push_back(model.neighbour_distance(i));
  const FillErrorReport ours = fill_error(truth, filled, gaps, normaliser);
  const FillErrorReport linear = fill_error(truth, fill_linear(apply_gaps(truth, gaps)), gaps, normaliser);
  EXPECT_EQ(ours.unfilled, 0);
  EXPECT_LT(ours.millimetres.mean, 30.0);
  EXPECT_LT(ours.normalised.mean, 0.12);
  EXPECT_LT(ours.millimetres.mean, 0.1 * linear.millimetres.mean);
  for (const Vec3& p : filled.positions) ASSERT_TRUE(p.allFinite());
}

// The long-gap protocol on shared real takes (first half trains, seeded 2-6 s gaps of three
// markers at once in the second): the online filler against the offline Gloersen PCA on the same
// gaps, with the targets of the accuracy issue (mean at most 1.5 times, maximum at most the
// offline one's), and no measured sample changed on the clean CMU and HDM05 takes. Measured
// (online / Gloersen, mean and max), before and after the regional PCA opinion:
//   CMU 85_12 seed 4: 0.58, 0.58 -> 0.58, 0.57;
//   HDM05 bd_05-01 seed 2: 1.58, 0.68 (mean target missed) -> 1.33, 0.68;
//   tennis serve seed 6: 1.54, 2.19 (both missed) -> 0.89, 0.94;
// and before and after the regions learned online and the opinions' variance grew with their
// misfit (HDM05's first half stands, its second walks):
//   HDM05 bd_05-01 seed 3: 1.70, 0.87 (mean target missed) -> 1.01, 0.82;
//   HDM05 bd_05-01 seed 5: 1.47, 1.24 (max target missed) -> 1.19, 0.89.
// The tennis serve's measured samples are not asserted: 1 changed in most runs (see
// docs/measurements-log.md).
TEST(SkinstreamCli, EvalFillLongGapsHoldUpAgainstTheOfflinePca) {
  struct Take {
    std::string capture;
    int seed;
    bool clean;  // no sample of it may be changed
  };
  const std::string captures = std::string(SKINSTREAM_SHARED_DIR) + "/data/captures/";
  for (const Take& take : {Take{"cmu/85_12.c3d", 4, true}, Take{"hdm05/HDM_bd_05-01_01_120.c3d", 2, true},
                           Take{"hdm05/HDM_bd_05-01_01_120.c3d", 3, true}, Take{"hdm05/HDM_bd_05-01_01_120.c3d", 5, true},
                           Take{"kineticstoolkit/kinematics_tennis_serve.c3d", 6, false}}) {
    SCOPED_TRACE(take.capture + " seed " + std::to_string(take.seed));
    const ProgramRun r = run_cli("eval-fill --capture " + captures + take.capture + " --seed " + std::to_string(take.seed) +
                             " --gap-protocol long --json");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto j = nlohmann::json::parse(r.output);
    EXPECT_EQ(j["gaps"]["protocol"], "long");
    EXPECT_GE(j["gaps"]["fraction_of_samples"].get<double>(), 0.04);
    EXPECT_GE(j["gaps"]["longest_frames"].get<int>(), static_cast<int>(2 * j["rate_hz"].get<double>()));
    EXPECT_LE(j["gaps"]["longest_frames"].get<int>(), static_cast<int>(6 * j["rate_hz"].get<double>()));
    nlohmann::json online, offline;
    for (const auto& m : j["methods"]) {
      if (m["name"] == "skinstream_online") online = m;
      if (m["name"] == "gloersen_pca") offline = m;
    }
    ASSERT_FALSE(online.is_null() || offline.is_null());
    EXPECT_EQ(online["unfilled"], 0);
    if (take.clean) {
      EXPECT_EQ(online["changed_measured_samples"], 0);
    }
    EXPECT_LE(online["mm"]["mean"].get<double>(), 1.5 * offline["mm"]["mean"].get<double>());
    EXPECT_LE(online["mm"]["max"].get<double>(), offline["mm"]["max"].get<double>());
    EXPECT_DOUBLE_EQ(j["online_to_gloersen"]["mean_ratio"].get<double>(),
                     online["mm"]["mean"].get<double>() / offline["mm"]["mean"].get<double>());
  }
}

// A short synthetic flexing take, with skinstream's relabeller and online filler judged against
// its truth by `synth --stats`. Asserts the targets of the synthetic-data issue on this gentle
// motion. Measured when written: 1.006 trajectories per marker after merging, 0.2% wrongly
// labelled fragments, 0.013 mean normalised error on deleted-then-filled samples.
TEST(SkinstreamCli, SynthStatsOnAShortFlexTakeMeetTheRelabelAndFillTargets) {
  const ProgramRun r = run_cli("synth --motion flex --seconds 2 --seed 3 --train-seconds 10 --stats --out " +
                           test::scratch_path("flex.c3d") + " --body " +
                           std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["markers"], 350);
  EXPECT_GT(j["trajectories_before_merging"].get<int>(), 350);
  const auto& s = j["skinstream"];
  EXPECT_LE(s["after_per_marker"].get<double>(), 1.1);
  EXPECT_LE(s["wrongly_labelled_rate"].get<double>(), 0.003);
  EXPECT_LE(s["deleted_then_filled_error"]["normalised"]["mean"].get<double>(), 0.015);
}

// The relabel target of the accuracy issue (wrongly labelled fragments at most 0.3%) on the
// measured configuration (`synth --motion M --seed 1 --stats`: 5 s takes, subject trained on the
// 20 s range of motion), causal (lookahead 0), per motion it asserts. Before the relabel changes
// of this test's commit: punch 0.83%, golf 1.11%; when written: punch 0.28%, golf 0.29%. The
// range of motion (1.17%) does not meet it yet and is not asserted.
TEST(SkinstreamCli, SynthStatsRelabelAtMostThreePerMilleOnFastMotions) {
  for (const std::string motion : {"punch", "golf"}) {
    SCOPED_TRACE(motion);
    const ProgramRun r = run_cli("synth --motion " + motion + " --seed 1 --stats --out " + test::scratch_path(motion + ".c3d") +
                             " --body " + std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto s = nlohmann::json::parse(r.output)["skinstream"];
    EXPECT_EQ(s["lookahead_frames"], 0);
    EXPECT_GT(s["trajectories_before_merging"].get<int>(), 1000);
    EXPECT_LE(s["wrongly_labelled_rate"].get<double>(), 0.003) << s["wrongly_labelled_by"];
    EXPECT_LE(s["after_per_marker"].get<double>(), 1.2);
  }
}

// eval-deform names where each method's maximum comes from: its worst covered vertices, the
// first of which carries the row's maximum, with the frame, the distance to the nearest marker
// and (part-based methods only) the vertex's part weights.
TEST(SkinstreamCli, EvalDeformNamesTheVerticesBehindEachMaximum) {
  const ProgramRun r = run_cli(quick_eval_deform());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto& take = j["takes"][0];
  const int vertices = j["vertices"], frames = take["frames_evaluated"].get<int>() * 4;  // stride 4
  ASSERT_EQ(take["methods"].size(), 6u);
  for (const auto& method : take["methods"]) {
    SCOPED_TRACE(method["method"].get<std::string>());
    const auto& worst = method["worst_vertices"];
    ASSERT_EQ(worst.size(), 3u);
    EXPECT_DOUBLE_EQ(worst[0]["error_mm"].get<double>(), method["vertex_max_mm"].get<double>());
    for (size_t i = 0; i < worst.size(); ++i) {
      if (i > 0) {
        EXPECT_LE(worst[i]["error_mm"].get<double>(), worst[i - 1]["error_mm"].get<double>());
      }
      EXPECT_GE(worst[i]["vertex"].get<int>(), 0);
      EXPECT_LT(worst[i]["vertex"].get<int>(), vertices);
      EXPECT_GE(worst[i]["frame"].get<int>(), 0);
      EXPECT_LT(worst[i]["frame"].get<int>(), frames);
      EXPECT_GT(worst[i]["nearest_marker_mm"].get<double>(), 0.0);
      EXPECT_FALSE(worst[i]["nearest_marker"].get<std::string>().empty());
      const bool part_based = !method["method"].get<std::string>().starts_with("lbs_");
      ASSERT_EQ(worst[i].contains("parts"), part_based);
      if (!part_based) continue;
      double sum = 0.0;
      for (const auto& part : worst[i]["parts"]) sum += part["weight"].get<double>();
      EXPECT_NEAR(sum, 1.0, 1e-9);
      // The part that alone would place it best (MeshDeformer::part, tested against the
      // blended mesh in mesh_deformer_test): one of the subject's parts.
      const auto& best = worst[i]["best_single_part"];
      EXPECT_GE(best["part"].get<int>(), 0);
      EXPECT_LT(best["part"].get<int>(), j["parts"].get<int>());
      EXPECT_GE(best["error_mm"].get<double>(), 0.0);
    }
  }
}

// Conventional LBS runs twice: with weights from the rest mesh and skeleton alone (bone heat) and,
// as an oracle, with the weights the synthetic truth is skinned with. The table's rule compares
// the full method with every row but the oracle, on mean and p95; the maxima are reported with
// the method that has the lowest and where the full method's occurs.
TEST(SkinstreamCli, EvalDeformHasAConventionalLbsRowBehindTheFullMethod) {
  const ProgramRun r = run_cli(quick_eval_deform());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto& methods = j["takes"][0]["methods"];
  auto row = [&](const std::string& name) -> const nlohmann::json& {
    for (const auto& m : methods)
      if (m["method"] == name) return m;
    ADD_FAILURE() << "no row " << name;
    return methods[0];
  };
  const auto& full = row("full");
  const auto& heat = row("lbs_bone_heat");
  EXPECT_FALSE(heat["oracle"].get<bool>());
  EXPECT_TRUE(row("lbs_truth_weights")["oracle"].get<bool>());
  EXPECT_LT(full["vertex_mean_mm"].get<double>(), heat["vertex_mean_mm"].get<double>());
  EXPECT_LT(full["vertex_p95_mm"].get<double>(), heat["vertex_p95_mm"].get<double>());
  // LBS moves the skin with its bones, and weights made without the truth are a different
  // deformation from the oracle's.
  EXPECT_NE(heat["vertex_mean_mm"], row("lbs_truth_weights")["vertex_mean_mm"]);
  const auto& rule = j["table_rule"];
  EXPECT_EQ(rule["takes"], 1);
  EXPECT_EQ(rule["met"], 1) << rule.dump(2);
  ASSERT_EQ(rule["maxima"].size(), 1u);
  EXPECT_EQ(rule["maxima"][0]["full_mm"], full["vertex_max_mm"]);
  EXPECT_EQ(rule["maxima"][0]["full_at"]["vertex"], full["worst_vertices"][0]["vertex"]);
}

// Issue 4's claim, checked on a subject no setting was chosen on: with the generator's seed 2
// (another body proportion, marker placement, noise and motion than seed 1, on which the
// method was developed), the full method has the lowest mean vertex error and marker mean of
// every row. Before eq. 6 had its ridge, its two 9-member parts lost this on both takes
// (breathe 1.25 and punch 3.71 mm against rigid + RBF's 1.12 and 3.26 mm, this command at
// 40d6cd0).
TEST(SkinstreamCli, EvalDeformFullMethodLeadsOnAHeldOutSubject) {
  const ProgramRun r = run_cli("eval-deform --seed 2 --motions breathe,punch --seconds 2 --json --body " +
                           std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["takes"].size(), 2u);
  for (const auto& take : j["takes"]) {
    SCOPED_TRACE(take["motion"].get<std::string>());
    const nlohmann::json* full = nullptr;
    for (const auto& method : take["methods"])
      if (method["method"] == "full") full = &method;
    ASSERT_NE(full, nullptr);
    for (const auto& method : take["methods"]) {
      if (&method == full) continue;
      SCOPED_TRACE(method["method"].get<std::string>());
      EXPECT_LT((*full)["vertex_mean_mm"].get<double>(), method["vertex_mean_mm"].get<double>());
      EXPECT_LT((*full)["marker_mean_mm"].get<double>(), method["marker_mean_mm"].get<double>());
    }
  }
}

// The ramp at hinge joints is on by default, half the subject's median nearest-marker spacing
// wide either side (the 350-marker layout: about 46 mm), and --no-joint-blend turns it into the
// hard switch: fewer vertices then blend two parts.
TEST(SkinstreamCli, EvalDeformJointRampAndItsSwitch) {
  const auto [r, h] = quick_eval_default_and("--no-joint-blend");
  ASSERT_FALSE(r.is_null() || h.is_null());
  ASSERT_FALSE(r["joints"].empty());
  EXPECT_EQ(r["joints"], h["joints"]);
  EXPECT_GT(r["joint_blend_mm"].get<double>(), 15.0);
  EXPECT_LT(r["joint_blend_mm"].get<double>(), 35.0);
  EXPECT_EQ(h["joint_blend_mm"].get<double>(), 0.0);
  EXPECT_GT(r["mean_parts_per_vertex"].get<double>(), h["mean_parts_per_vertex"].get<double>());
}

// The marker weights' part boundary is a ring of the marker surface wider than the paper's by
// default; --boundary-rings 0 gives the paper's (fewer markers weighed by likelihood, the same
// parts), and a negative count is refused before any work.
TEST(SkinstreamCli, EvalDeformBoundaryRings) {
  const auto [w, p] = quick_eval_default_and("--boundary-rings 0");
  ASSERT_FALSE(w.is_null() || p.is_null());
  EXPECT_EQ(w["boundary_rings"], 1);
  EXPECT_EQ(p["boundary_rings"], 0);
  EXPECT_EQ(w["parts"], p["parts"]);
  for (size_t k = 0; k < w["part_sizes"].size(); ++k)
    EXPECT_EQ(w["part_sizes"][k]["triangles"], p["part_sizes"][k]["triangles"]);
  EXPECT_GT(w["boundary_markers"].get<int>(), p["boundary_markers"].get<int>());
  EXPECT_GT(w["mean_parts_per_vertex"].get<double>(), p["mean_parts_per_vertex"].get<double>());
  const ProgramRun negative = run_cli(quick_eval_deform() + " --boundary-rings -1");
  EXPECT_NE(negative.exit_code, 0);
  EXPECT_NE(negative.output.find("--boundary-rings"), std::string::npos) << negative.output;
}

// Inside folds, and in a band half a marker spacing around them, the vertex weights are smoothed
// over the mesh by default (a few hundred of the 13,380 vertices, at the armpits and the groin);
// --no-fold-smoothing keeps the fold blend's weights as they are, with the same parts and joints.
TEST(SkinstreamCli, EvalDeformFoldSmoothing) {
  const auto [smoothed, blend_only] = quick_eval_default_and("--no-fold-smoothing");
  ASSERT_FALSE(smoothed.is_null() || blend_only.is_null());
  EXPECT_GT(smoothed["fold_smoothed_vertices"].get<int>(), 100);
  EXPECT_LT(smoothed["fold_smoothed_vertices"].get<int>(), 2000);
  EXPECT_EQ(blend_only["fold_smoothed_vertices"], 0);
  // The band around the folds: half the median marker spacing, as the joints' ramp (about 23 mm).
  EXPECT_EQ(smoothed["fold_band_mm"], smoothed["joint_blend_mm"]);
  EXPECT_EQ(smoothed["parts"], blend_only["parts"]);
  EXPECT_EQ(smoothed["joints"], blend_only["joints"]);
  EXPECT_NE(smoothed["mean_parts_per_vertex"], blend_only["mean_parts_per_vertex"]);
}

// eval-deform measures a user's segmentation too: the parts it used written per marker
// (--part-file-out), and a hand-made file (--part-file: here the left side against the rest)
// building the model from exactly those parts; a file naming an unknown marker is refused.
TEST(SkinstreamCli, EvalDeformReadsAndWritesPartFiles) {
  const std::string base = quick_eval_deform();
  const std::string written = test::scratch_path("eval_parts.json"), sides = test::scratch_path("eval_sides.json");
  const ProgramRun automatic = run_cli(base + " --part-file-out " + written);
  ASSERT_EQ(automatic.exit_code, 0) << automatic.output;
  const auto a = nlohmann::json::parse(automatic.output);
  ASSERT_EQ(a["part_sizes"].size(), a["parts"].get<size_t>());
  nlohmann::json file;
  std::ifstream(written) >> file;
  ASSERT_EQ(file.size(), a["markers"].get<size_t>());

  nlohmann::json by_side = nlohmann::json::object();
  for (const auto& [name, part] : file.items()) by_side[name] = name.find("_L_") != std::string::npos ? 1 : 0;
  std::ofstream(sides) << by_side.dump();
  const ProgramRun two = run_cli(base + " --part-file " + sides);
  ASSERT_EQ(two.exit_code, 0) << two.output;
  const auto b = nlohmann::json::parse(two.output);
  EXPECT_EQ(b["parts"], 2);
  EXPECT_TRUE(b["part_file_unused_parts"].empty());
  int triangles_a = 0, triangles_b = 0;
  for (const auto& p : a["part_sizes"]) triangles_a += p["triangles"].get<int>();
  for (const auto& p : b["part_sizes"]) triangles_b += p["triangles"].get<int>();
  EXPECT_EQ(triangles_b, triangles_a);
  // Two parts cannot follow the body as well as the automatic ones: the rigid rows say so.
  auto mean_of = [](const nlohmann::json& j, const char* method) {
    for (const auto& m : j["takes"][0]["methods"])
      if (m["method"] == method) return m["vertex_mean_mm"].get<double>();
    return -1.0;
  };
  EXPECT_GT(mean_of(b, "rigid"), mean_of(a, "rigid"));

  std::ofstream(sides) << R"({"no_such_marker": 0})";
  const ProgramRun bad = run_cli(base + " --part-file " + sides);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("unknown marker \"no_such_marker\""), std::string::npos) << bad.output;
}

TEST(SkinstreamCli, SynthRefusesAnUnknownMotion) {
  const ProgramRun r = run_cli("synth --motion moonwalk --out " + test::scratch_path("m.c3d"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("moonwalk"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace skinstream
