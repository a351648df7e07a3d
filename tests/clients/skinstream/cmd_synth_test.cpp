// skinstream synth, run in-process on the shared MakeHuman body: the take, its truth and the
// meshes asked for are written, the printed counts are the files', and the seed decides it all.
#include "clients/skinstream/cmd_synth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "protocol/files/capture_file.h"
#include "support/test_data.h"
#include "tests/clients/skinstream/command_output.h"

namespace skinstream {
namespace {

// A quarter-second flexing take (30 frames), 4 meshes (frames 0, 8, 16, 24).
cli::SynthOptions short_take(const std::string& name) {
  cli::CommandLine c;
  const std::string dir = test::scratch_path(name);
  EXPECT_FALSE(test::parse_words({"synth", "--motion", "flex", "--seconds", "0.25", "--seed", "2", "--out", dir + ".c3d",
                                  "--truth", dir + "_truth.c3d", "--mesh-out-every", "8", dir + "_meshes", "--body",
                                  test::shared_path("data/meshes/makehuman")},
                                 c)
                   .has_value());
  return c.synth;
}

TEST(SynthCommand, WritesTheTakeItsTruthAndTheMeshes) {
  const cli::SynthOptions o = short_take("synth_command");
  const test::CommandOutput r = test::run_command(cli::run_synth, o);
  ASSERT_EQ(r.exit_code, 0);
  const Capture take = read_capture(o.out_path), truth = read_capture(o.truth_path);
  const int frames = static_cast<int>(std::lround(o.take.seconds * o.take.rate_hz));
  EXPECT_EQ(take.frame_count, frames);
  EXPECT_EQ(truth.frame_count, frames);
  const CaptureSummary summary = summarize(take);
  EXPECT_EQ(summary.labelled, o.take.markers);
  EXPECT_GT(summary.missing_fraction, 0.0);  // broken as a capture system delivers it
  EXPECT_EQ(summarize(truth).missing_fraction, 0.0);

  char expected[256];
  std::snprintf(expected, sizeof expected,
                "wrote %s: %d markers + %d unlabelled channels, %d frames at 120 Hz, %.1f%% of labelled samples missing\n",
                o.out_path.c_str(), summary.labelled, summary.unlabelled, frames, 100.0 * summary.missing_fraction);
  EXPECT_EQ(r.text.rfind(expected, 0), 0u) << r.text;
  EXPECT_NE(r.text.find("wrote " + o.truth_path + ": truth\n"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("wrote 4 meshes"), std::string::npos) << r.text;
  for (const char* mesh : {"mesh_000000.ply", "mesh_000008.ply", "mesh_000016.ply", "mesh_000024.ply"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(o.mesh_dir) / mesh)) << mesh;
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::path(o.mesh_dir) / "mesh_000032.ply"));
}

TEST(SynthCommand, TheSeedDecidesTheTake) {
  cli::SynthOptions a = short_take("synth_seed_a"), b = short_take("synth_seed_b"), c = short_take("synth_seed_c");
  c.take.seed = 3;
  for (const cli::SynthOptions* o : {&a, &b, &c}) ASSERT_EQ(test::run_command(cli::run_synth, *o).exit_code, 0);
  EXPECT_EQ(test::read_bytes(a.out_path), test::read_bytes(b.out_path));
  EXPECT_NE(test::read_bytes(a.out_path), test::read_bytes(c.out_path));
}

TEST(SynthCommand, AMissingBodyFolderIsAnError) {
  cli::SynthOptions o = short_take("synth_no_body");
  o.body_dir = test::scratch_path("no_such_body");
  EXPECT_ANY_THROW(test::run_command(cli::run_synth, o));
  EXPECT_FALSE(std::filesystem::exists(o.out_path));
}

}  // namespace
}  // namespace skinstream
