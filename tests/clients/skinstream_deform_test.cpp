// `skinstream deform` run as a user would, on the demo subject (ctest fixture demo_subject: the
// subdivided MakeHuman body registered to the synthetic seed-1 markers) and short takes of the
// same markers made with `skinstream synth`: the files it writes read back with the project's
// readers and agree with each other, and bad inputs fail with a clear error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "protocol/files/capture_file.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/point_cache.h"
#include "support/cli_run.h"
#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

namespace fs = std::filesystem;
using test::ProgramRun;
using test::run_cli;

const std::string kSubject = std::string(SKINSTREAM_DEMO_DIR) + "/subject.sksubj";

// A 0.1 s punching take (12 frames) of the demo subject's markers: the capture system's view
// (occlusions, unlabelled channels) and the truth (every marker every frame).
struct ShortTake {
  std::string observed = test::scratch_path("punch.c3d");
  std::string truth = test::scratch_path("punch_truth.c3d");
  ShortTake() {
    const ProgramRun r = run_cli("synth --motion punch --seconds 0.1 --seed 1 --body " + test::source_path("replay_data/makehuman") +
                             " --out " + observed + " --truth " + truth);
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
};

std::vector<std::string> files_named(const std::string& dir, const std::string& prefix) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().rfind(prefix, 0) == 0) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The JSON object the command prints (stdout; any stderr line after it has no braces).
nlohmann::json summary(const std::string& output) {
  const size_t at = output.find('{');
  return nlohmann::json::parse(output.substr(at, output.rfind('}') - at + 1));
}

TEST(SkinstreamDeform, PlyFramesAndThePointCacheHoldTheSameMeshes) {
  const ShortTake take;
  const std::string out = test::scratch_path("ply");
  const ProgramRun r = run_cli("deform --subject " + kSubject + " --capture " + take.truth + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json s = summary(r.output);
  EXPECT_EQ(s["frames"], 12);
  EXPECT_EQ(s["frames_with_missing_markers"], 0);

  const Capture capture = read_capture(take.truth);
  const std::vector<std::string> frames = files_named(out, "frame_");
  ASSERT_EQ(frames.size(), 12u);
  char first[32];
  std::snprintf(first, sizeof first, "frame_%06d.ply", capture.first_frame);
  EXPECT_EQ(frames.front(), first);

  const TriangleMesh rest = read_mesh(out + "/rest.obj");
  const PointCache cache = read_point_cache(out + "/deformed.pc2");
  ASSERT_EQ(cache.point_count, static_cast<int>(rest.vertices.size()));
  ASSERT_EQ(cache.sample_count, 12);
  EXPECT_EQ(cache.start_frame, static_cast<float>(capture.first_frame));
  for (int f : {0, 11}) {
    const TriangleMesh mesh = read_mesh(out + "/" + frames[f]);
    ASSERT_EQ(mesh.vertices.size(), rest.vertices.size());
    EXPECT_EQ(mesh.faces, rest.faces);
    double worst = 0.0, moved = 0.0;
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      worst = std::max(worst, (mesh.vertices[v] - cache.at(f, static_cast<int>(v))).norm());
      moved = std::max(moved, (mesh.vertices[v] - rest.vertices[v]).norm());
    }
    EXPECT_LT(worst, 1e-3) << frames[f];  // both float32
    // Every synthetic take starts in the subject's reference pose, which deforms to the rest
    // mesh; 0.1 s into the punch the arm has moved.
    if (f == 0) EXPECT_LT(moved, 0.01);
    else EXPECT_GT(moved, 10.0);
  }
}

TEST(SkinstreamDeform, ObjFramesCarryUnitNormals) {
  const ShortTake take;
  const std::string out = test::scratch_path("obj");
  const ProgramRun r = run_cli("deform --subject " + kSubject + " --capture " + take.truth + " --out " + out + " --format obj --no-pc2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(out + "/deformed.pc2"));
  const std::vector<std::string> frames = files_named(out, "frame_");
  ASSERT_EQ(frames.size(), 12u);
  std::ifstream in(out + "/" + frames.back());
  int normals = 0, vertices = 0;
  double worst = 0.0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("v ", 0) == 0) ++vertices;
    if (line.rfind("vn ", 0) != 0) continue;
    double x, y, z;
    ASSERT_EQ(std::sscanf(line.c_str() + 3, "%lf %lf %lf", &x, &y, &z), 3) << line;
    worst = std::max(worst, std::abs(std::sqrt(x * x + y * y + z * z) - 1.0));
    ++normals;
  }
  EXPECT_EQ(normals, vertices);
  EXPECT_GT(vertices, 50000);
  EXPECT_LT(worst, 1e-5);
}

TEST(SkinstreamDeform, Pc2FormatWritesThePointCacheAlone) {
  const ShortTake take;
  const std::string out = test::scratch_path("pc2");
  const ProgramRun r = run_cli("deform --subject " + kSubject + " --capture " + take.truth + " --out " + out + " --format pc2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(files_named(out, "frame_").empty());
  EXPECT_EQ(read_point_cache(out + "/deformed.pc2").sample_count, 12);

  const ProgramRun nothing =
      run_cli("deform --subject " + kSubject + " --capture " + take.truth + " --out " + out + " --format pc2 --no-pc2");
  EXPECT_NE(nothing.exit_code, 0);
  EXPECT_NE(nothing.output.find("nothing would be written"), std::string::npos) << nothing.output;
}

// The capture system's view has occluded markers: without --fill those frames repeat the previous
// shape and the command says so (exit 2); with --fill every frame is deformed.
TEST(SkinstreamDeform, GapsNeedFillAndAreReported) {
  const ShortTake take;
  const Capture observed = read_capture(take.observed);
  int frames_with_gaps = 0;
  for (int f = 0; f < observed.frame_count; ++f)
    for (size_t c = 0; c < observed.labels.size(); ++c)
      if (!observed.at(f, static_cast<int>(c)).allFinite()) {
        ++frames_with_gaps;
        break;
      }
  ASSERT_GT(frames_with_gaps, 0) << "the synthetic take has no occlusion to test with";

  const std::string out = test::scratch_path("gaps");
  const ProgramRun raw = run_cli("deform --subject " + kSubject + " --capture " + take.observed + " --out " + out + " --format none");
  EXPECT_EQ(raw.exit_code, 2) << raw.output;
  EXPECT_NE(raw.output.find("use --fill"), std::string::npos) << raw.output;
  EXPECT_GT(summary(raw.output)["frames_with_missing_markers"].get<int>(), 0);

  const ProgramRun filled =
      run_cli("deform --subject " + kSubject + " --capture " + take.observed + " --out " + out + " --format none --fill");
  ASSERT_EQ(filled.exit_code, 0) << filled.output;
  EXPECT_EQ(summary(filled.output)["frames_with_missing_markers"], 0);
  EXPECT_EQ(read_point_cache(out + "/deformed.pc2").sample_count, observed.frame_count);
}

TEST(SkinstreamDeform, RefusesASubjectWithoutAMesh) {
  const std::string subject = test::scratch_path("markers_only.sksubj");
  ASSERT_EQ(run_cli("build-subject --capture " + test::source_path("replay_data/cmu/85_12.c3d") + " --out " + subject).exit_code, 0);
  const ProgramRun r = run_cli("deform --subject " + subject + " --capture " + test::source_path("replay_data/cmu/85_12.c3d") +
                           " --out " + test::scratch_path("none"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no detailed mesh"), std::string::npos) << r.output;
}

TEST(SkinstreamDeform, RefusesACaptureOfOtherMarkers) {
  const ShortTake take;
  Capture other = read_capture(take.truth);
  for (auto& label : other.labels) label = "X" + label;
  const std::string path = test::scratch_path("other.c3d");
  write_capture(other, path);
  const ProgramRun r = run_cli("deform --subject " + kSubject + " --capture " + path + " --out " + test::scratch_path("other"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("have no channel"), std::string::npos) << r.output;
}

TEST(SkinstreamDeform, RefusesAnUnknownFormat) {
  const ShortTake take;
  const ProgramRun r =
      run_cli("deform --subject " + kSubject + " --capture " + take.truth + " --out " + test::scratch_path("x") + " --format stl");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("stl"), std::string::npos) << r.output;
}


// build-subject's segmentation written out (--part-file-out) and read back (--part-file), as a
// technician adjusting the parts by hand would, on the demo fixture's inputs (20 s range of
// motion, the subdivided body already on the markers).
class SkinstreamPartFile : public ::testing::Test {
 protected:
  const std::string demo = SKINSTREAM_DEMO_DIR;
  std::string build(const std::string& extra, const std::string& name) {
    return "build-subject --capture " + demo + "/rom_truth.c3d --reference-frame 0 --mesh " + demo +
           "/rest/mesh_000000.ply --no-register --marker-offset 4 --out " + test::scratch_path(name + ".sksubj") + " " + extra;
  }
  static nlohmann::json read_json(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
  }
};

TEST_F(SkinstreamPartFile, WrittenPartsReadBackAndUnusedOnesAreReported) {
  const std::string first = test::scratch_path("parts_a.json"), second = test::scratch_path("parts_b.json");
  const ProgramRun a = run_cli(build("--part-file-out " + first, "a"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const nlohmann::json report_a = summary(a.output)["mesh"];
  const int parts = report_a["parts"];
  ASSERT_EQ(report_a["part_sizes"].size(), static_cast<size_t>(parts));
  int triangles = 0;
  for (const auto& p : report_a["part_sizes"]) {
    EXPECT_GT(p["triangles"].get<int>(), 0);
    EXPECT_GE(p["members"].get<int>(), 3);
    EXPECT_GE(p["rigid_rms_mm"].get<double>(), 0.0);
    triangles += p["triangles"].get<int>();
  }
  EXPECT_EQ(triangles, summary(a.output)["triangles"].get<int>());

  // One entry per marker (every marker of the demo surface is in a triangle), a part each.
  const nlohmann::json file_a = read_json(first);
  EXPECT_EQ(file_a.size(), summary(a.output)["markers"].get<size_t>());
  for (const auto& [marker, part] : file_a.items()) {
    ASSERT_TRUE(part.is_number_integer()) << marker;
    EXPECT_GE(part.get<int>(), 0);
    EXPECT_LT(part.get<int>(), parts);
  }

  // Read back, every index up to the largest the file names is kept or reported unused. Per
  // marker is not exact: a part that no marker mostly belongs to (a few triangles between
  // others) cannot be named, and a small part can be outvoted on its triangles.
  auto check_read_back = [](const nlohmann::json& file, const ProgramRun& run_back) {
    std::set<int> named;
    for (const auto& [marker, part] : file.items()) named.insert(part.get<int>());
    const nlohmann::json report = summary(run_back.output)["mesh"];
    const std::vector<int> unused = report["part_file_unused_parts"];
    for (int p = 0; p <= *named.rbegin(); ++p)
      if (!named.count(p)) {
        EXPECT_NE(std::find(unused.begin(), unused.end(), p), unused.end()) << "part " << p;
      }
    EXPECT_EQ(report["parts"].get<int>() + static_cast<int>(unused.size()), *named.rbegin() + 1);
    if (!unused.empty()) {
      EXPECT_NE(run_back.output.find("hold no triangle"), std::string::npos) << run_back.output;
    }
  };
  const ProgramRun b = run_cli(build("--part-file " + first + " --part-file-out " + second, "b"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  check_read_back(file_a, b);
  const ProgramRun c = run_cli(build("--part-file " + second, "c"));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  check_read_back(read_json(second), c);
}

TEST_F(SkinstreamPartFile, BadPartFilesAndMissingMeshAreRefused) {
  const std::string bad = test::scratch_path("parts_bad.json");
  std::ofstream(bad) << "{\"not_a_marker\": 0}\n";
  const ProgramRun unknown = run_cli(build("--part-file " + bad, "bad"));
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("unknown marker \"not_a_marker\""), std::string::npos) << unknown.output;
  std::ofstream(bad) << "{}\n";
  const ProgramRun empty = run_cli(build("--part-file " + bad, "empty"));
  EXPECT_NE(empty.exit_code, 0);
  EXPECT_NE(empty.output.find("has no part"), std::string::npos) << empty.output;
  const ProgramRun no_mesh = run_cli("build-subject --capture " + demo + "/rom_truth.c3d --out " + test::scratch_path("x.sksubj") +
                                 " --part-file-out " + test::scratch_path("x.json"));
  EXPECT_NE(no_mesh.exit_code, 0);
  EXPECT_NE(no_mesh.output.find("--part-file-out needs --mesh"), std::string::npos) << no_mesh.output;
  const ProgramRun ignored = run_cli("build-subject --capture " + demo + "/rom_truth.c3d --out " + test::scratch_path("y.sksubj") +
                                 " --part-file " + bad);
  EXPECT_NE(ignored.exit_code, 0);
  EXPECT_NE(ignored.output.find("--part-file needs --mesh"), std::string::npos) << ignored.output;
}

}  // namespace
}  // namespace skinstream
