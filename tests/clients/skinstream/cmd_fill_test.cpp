// skinstream fill, parsed from a command line and run in-process: a subject built from one real
// take fills seeded gaps deleted from another, and its JSON accounts for every sample.
#include "clients/skinstream/cmd_fill.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "clients/skinstream/cmd_build_subject.h"
#include "core/evaluation/gap_plan.h"
#include "protocol/files/capture_file.h"
#include "support/cli_run.h"
#include "support/test_data.h"
#include "tests/clients/skinstream/command_output.h"

namespace skinstream {
namespace {

using test::kCmu02;
using test::kCmu12;

class FillCommand : public ::testing::Test {
 protected:
  // One subject (trained on 85_12) and one gapped 85_02 for the suite.
  static void SetUpTestSuite() {
    cli::BuildSubjectOptions build;
    build.capture_path = kCmu12;
    build.out_path = test::scratch_path("fill_command.subject");
    ASSERT_EQ(test::run_command(cli::run_build_subject, build).exit_code, 0);
    subject_path = build.out_path;
    truth = read_capture(kCmu02);
    GapPlanOptions plan;
    plan.seed = 5;
    gaps = plan_gaps(truth, plan);
    gapped_path = test::scratch_path("fill_command_gaps.c3d");
    write_capture(apply_gaps(truth, gaps), gapped_path);
  }
  static cli::FillOptions parse(std::vector<std::string> words) {
    cli::CommandLine c;
    EXPECT_FALSE(test::parse_words(words, c).has_value());
    return c.fill;
  }
  static inline std::string subject_path, gapped_path;
  static inline Capture truth;
  static inline std::vector<Gap> gaps;
};

TEST_F(FillCommand, AccountsForEverySampleAndTheLatencyAsked) {
  const std::string out_path = test::scratch_path("fill_command_online.c3d");
  const cli::FillOptions o = parse({"fill", "--subject", subject_path, gapped_path, "--out", out_path, "--lookahead", "4",
                                    "--smooth", "online", "--smooth-lookahead", "3"});
  const test::CommandOutput r = test::run_command(cli::run_fill, o);
  ASSERT_EQ(r.exit_code, 0) << r.text;
  const auto j = nlohmann::json::parse(r.text);
  EXPECT_EQ(j["input"], gapped_path);
  EXPECT_EQ(j["output"], out_path);
  EXPECT_EQ(j["frames"], truth.frame_count);
  const int markers = j["markers"];
  EXPECT_EQ(markers, static_cast<int>(truth.labelled_points().size()));
  const auto& s = j["samples"];
  EXPECT_EQ(s["measured"].get<long>() + s["relabelled"].get<long>() + s["filled"].get<long>() + s["held"].get<long>(),
            static_cast<long>(truth.frame_count) * markers);
  long deleted = 0;
  for (const Gap& g : gaps) deleted += g.length;
  EXPECT_GE(s["filled"].get<long>() + s["held"].get<long>(), deleted);
  EXPECT_TRUE(j["absent_markers"].empty());
  EXPECT_EQ(j["latency_frames"], 4 + 3);  // the gap-end lookahead and the smoothing's
  EXPECT_DOUBLE_EQ(j["latency_ms"].get<double>(), 7 * 1000.0 / truth.rate_hz);

  const Capture filled = read_capture(out_path);
  EXPECT_EQ(filled.labels, truth.labels);
  EXPECT_EQ(filled.frame_count, truth.frame_count);
  for (const Vec3& p : filled.positions) ASSERT_TRUE(is_present(p) && p.allFinite());
}

// The rigid estimate alone (eq. 2) fills the same gaps differently from the PCA: the option
// reaches the filler.
TEST_F(FillCommand, NoPcaChangesTheFilledSamplesOnly) {
  const std::string with_pca = test::scratch_path("fill_command_pca.c3d"), rigid = test::scratch_path("fill_command_rigid.c3d");
  ASSERT_EQ(test::run_command(cli::run_fill, parse({"fill", "--subject", subject_path, gapped_path, "--out", with_pca})).exit_code, 0);
  ASSERT_EQ(test::run_command(cli::run_fill, parse({"fill", "--subject", subject_path, gapped_path, "--out", rigid, "--no-pca"}))
                .exit_code,
            0);
  const Capture a = read_capture(with_pca), b = read_capture(rigid), gapped = read_capture(gapped_path);
  ASSERT_EQ(a.positions.size(), gapped.positions.size());
  long differ_in_gaps = 0, differ_outside = 0;
  for (size_t k = 0; k < a.positions.size(); ++k) {
    const bool differ = (a.positions[k] - b.positions[k]).norm() > 1e-6;
    (is_present(gapped.positions[k]) ? differ_outside : differ_in_gaps) += differ;
  }
  EXPECT_GT(differ_in_gaps, 0);
  EXPECT_EQ(differ_outside, 0);
}

TEST_F(FillCommand, RefusesASubjectOfOtherMarkersAndWritesNothing) {
  Capture renamed = read_capture(kCmu02);
  for (auto& label : renamed.labels) label = "X" + label;
  const std::string other = test::scratch_path("fill_command_other_labels.c3d");
  write_capture(renamed, other);
  cli::FillOptions o;
  o.subject_path = subject_path;
  o.in_path = other;
  o.out_path = test::scratch_path("fill_command_never.c3d");
  try {
    test::run_command(cli::run_fill, o);
    ADD_FAILURE() << "filled a capture with none of the subject's markers";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("none of the subject"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(o.out_path));
}

}  // namespace
}  // namespace skinstream
