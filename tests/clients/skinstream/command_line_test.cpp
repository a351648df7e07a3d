// skinstream's command line parsed into each command's options: the defaults are the core's
// own, every option lands in its field, and bad values are refused before anything runs.
#include "clients/skinstream/command_line.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "tests/clients/skinstream/command_output.h"

namespace skinstream {
namespace {

using cli::CommandLine;
using test::parse_words;

// Parses `words`, expecting the command to go ahead.
CommandLine parsed(const std::vector<std::string>& words) {
  CommandLine c;
  const std::optional<int> exit_code = parse_words(words, c);
  EXPECT_FALSE(exit_code.has_value()) << "exit code " << exit_code.value_or(0);
  return c;
}

// Parses `words`, expecting a usage error: the exit code, never 0.
int refused(const std::vector<std::string>& words) {
  CommandLine c;
  const std::optional<int> exit_code = parse_words(words, c);
  EXPECT_TRUE(exit_code.has_value());
  EXPECT_TRUE(c.command.empty()) << c.command;
  return exit_code.value_or(0);
}

TEST(CommandLine, NoCommandIsAUsageErrorAndHelpIsNot) {
  EXPECT_NE(refused({}), 0);
  EXPECT_NE(refused({"moonwalk"}), 0);
  CommandLine c;
  EXPECT_EQ(parse_words({"fill", "--help"}, c), std::optional<int>(0));
}

TEST(CommandLine, FillDefaultsAreTheFillersOwn) {
  const CommandLine c = parsed({"fill", "--subject", "s.subject", "in.c3d", "--out", "out.c3d"});
  ASSERT_EQ(c.command, "fill");
  EXPECT_EQ(c.fill.subject_path, "s.subject");
  EXPECT_EQ(c.fill.in_path, "in.c3d");
  EXPECT_EQ(c.fill.out_path, "out.c3d");
  const CaptureFillOptions defaults;
  EXPECT_EQ(c.fill.fill.lookahead, defaults.lookahead);
  EXPECT_EQ(c.fill.fill.smoothing, SmoothingMode::None);
  EXPECT_EQ(c.fill.fill.smoothing_options.lookahead, defaults.smoothing_options.lookahead);
  EXPECT_EQ(c.fill.fill.filler.continuity_seconds, defaults.filler.continuity_seconds);
  EXPECT_TRUE(c.fill.fill.filler.use_pca);
}

TEST(CommandLine, FillTakesEachOption) {
  const CommandLine c = parsed({"fill", "--subject", "s", "in.c3d", "--out", "o.c3d", "--lookahead", "6", "--smooth", "online",
                                "--smooth-lookahead", "4", "--continuity-seconds", "0.5", "--no-pca"});
  EXPECT_EQ(c.fill.fill.lookahead, 6);
  EXPECT_EQ(c.fill.fill.smoothing, SmoothingMode::Online);
  EXPECT_EQ(c.fill.fill.smoothing_options.lookahead, 4);
  EXPECT_EQ(c.fill.fill.filler.continuity_seconds, 0.5);
  EXPECT_FALSE(c.fill.fill.filler.use_pca);
  EXPECT_EQ(parsed({"fill", "--subject", "s", "i", "--out", "o", "--smooth", "offline"}).fill.fill.smoothing,
            SmoothingMode::Offline);
}

TEST(CommandLine, FillRefusesBadValues) {
  EXPECT_NE(refused({"fill", "--subject", "s", "in.c3d", "--out", "o.c3d", "--lookahead", "241"}), 0);
  EXPECT_NE(refused({"fill", "--subject", "s", "in.c3d", "--out", "o.c3d", "--smooth", "sideways"}), 0);
  EXPECT_NE(refused({"fill", "in.c3d", "--out", "o.c3d"}), 0);  // no subject
}

TEST(CommandLine, EvalFillDefaults) {
  const CommandLine c = parsed({"eval-fill", "--capture", "take.c3d"});
  ASSERT_EQ(c.command, "eval-fill");
  const cli::EvalFillOptions& o = c.eval_fill;
  EXPECT_EQ(o.capture_path, "take.c3d");
  EXPECT_TRUE(o.train_path.empty());
  EXPECT_EQ(o.split, 0.5);
  EXPECT_EQ(o.gap_protocol, "short");
  EXPECT_EQ(o.lookahead, 6);
  EXPECT_FALSE(o.ablations);
  EXPECT_FALSE(o.json);
  const GapPlanOptions plan;
  EXPECT_EQ(o.gaps.seed, plan.seed);
  EXPECT_EQ(o.gaps.max_seconds, plan.max_seconds);
  EXPECT_EQ(o.gaps.gaps_per_marker_per_minute, plan.gaps_per_marker_per_minute);
}

TEST(CommandLine, EvalFillTakesEachOption) {
  const CommandLine c = parsed({"eval-fill", "--capture", "take.c3d", "--train", "rom.c3d", "--split", "0.3", "--seed", "9",
                                "--gap-protocol", "long", "--max-gap-seconds", "2", "--gaps-per-minute", "3", "--lookahead",
                                "12", "--ablations", "--json"});
  const cli::EvalFillOptions& o = c.eval_fill;
  EXPECT_EQ(o.train_path, "rom.c3d");
  EXPECT_EQ(o.split, 0.3);
  EXPECT_EQ(o.gaps.seed, 9u);
  EXPECT_EQ(o.gap_protocol, "long");
  EXPECT_EQ(o.gaps.max_seconds, 2.0);
  EXPECT_EQ(o.gaps.gaps_per_marker_per_minute, 3.0);
  EXPECT_EQ(o.lookahead, 12);
  EXPECT_TRUE(o.ablations);
  EXPECT_TRUE(o.json);
}

TEST(CommandLine, EvalFillRefusesBadValues) {
  EXPECT_NE(refused({"eval-fill", "--capture", "take.c3d", "--split", "0.95"}), 0);
  EXPECT_NE(refused({"eval-fill", "--capture", "take.c3d", "--gap-protocol", "medium"}), 0);
  EXPECT_NE(refused({"eval-fill", "--split", "0.5"}), 0);  // no capture
}

TEST(CommandLine, SynthDefaultsAreTheGeneratorsOwn) {
  const CommandLine c = parsed({"synth", "--out", "take.c3d"});
  ASSERT_EQ(c.command, "synth");
  const synth::SynthOptions defaults;
  const cli::SynthOptions& o = c.synth;
  EXPECT_EQ(o.out_path, "take.c3d");
  EXPECT_EQ(o.take.motion, defaults.motion);
  EXPECT_EQ(o.take.seconds, defaults.seconds);
  EXPECT_EQ(o.take.seed, defaults.seed);
  EXPECT_EQ(o.take.markers, defaults.markers);
  EXPECT_EQ(o.take.subdivided, defaults.subdivided);
  EXPECT_EQ(o.take.deform, defaults.deform);
  EXPECT_TRUE(o.truth_path.empty());
  EXPECT_EQ(o.mesh_every, 0);
  EXPECT_TRUE(o.body_dir.empty());
  EXPECT_FALSE(o.stats);
  EXPECT_EQ(o.train_seconds, 20.0);
}

TEST(CommandLine, SynthTakesEachOption) {
  const CommandLine c = parsed({"synth", "--motion", "flex", "--seconds", "2.5", "--seed", "7", "--markers", "200", "--out",
                                "take.trc", "--truth", "truth.c3d", "--mesh-out-every", "10", "meshes", "--subdivided",
                                "--no-deform", "--body", "body", "--stats", "--train-seconds", "30"});
  const cli::SynthOptions& o = c.synth;
  EXPECT_EQ(o.take.motion, "flex");
  EXPECT_EQ(o.take.seconds, 2.5);
  EXPECT_EQ(o.take.seed, 7u);
  EXPECT_EQ(o.take.markers, 200);
  EXPECT_EQ(o.out_path, "take.trc");
  EXPECT_EQ(o.truth_path, "truth.c3d");
  EXPECT_EQ(o.mesh_every, 10);
  EXPECT_EQ(o.mesh_dir, "meshes");
  EXPECT_TRUE(o.take.subdivided);
  EXPECT_FALSE(o.take.deform);
  EXPECT_EQ(o.body_dir, "body");
  EXPECT_TRUE(o.stats);
  EXPECT_EQ(o.train_seconds, 30.0);
}

TEST(CommandLine, SynthRefusesBadValues) {
  EXPECT_NE(refused({"synth", "--out", "t.c3d", "--motion", "moonwalk"}), 0);
  EXPECT_NE(refused({"synth", "--out", "t.c3d", "--seconds", "0"}), 0);
  EXPECT_NE(refused({"synth", "--out", "t.c3d", "--markers", "5"}), 0);
  EXPECT_NE(refused({"synth", "--out", "t.c3d", "--mesh-out-every", "10"}), 0);  // N without DIR
  // N is judged by the command once the line is parsed: an error (exit 1), not a usage error.
  CommandLine c;
  EXPECT_THROW(parse_words({"synth", "--out", "t.c3d", "--mesh-out-every", "0", "meshes"}, c), std::invalid_argument);
  EXPECT_THROW(parse_words({"synth", "--out", "t.c3d", "--mesh-out-every", "ten", "meshes"}, c), std::invalid_argument);
  // ... after the usage errors.
  EXPECT_NE(refused({"synth", "--mesh-out-every", "0", "meshes"}), 0);
}

TEST(CommandLine, ConvertTakesTwoFiles) {
  const CommandLine c = parsed({"convert", "in.c3d", "out.trc"});
  ASSERT_EQ(c.command, "convert");
  EXPECT_EQ(c.convert.in_path, "in.c3d");
  EXPECT_EQ(c.convert.out_path, "out.trc");
  EXPECT_NE(refused({"convert", "in.c3d"}), 0);
  EXPECT_NE(refused({"convert", "in.c3d", "out.trc", "third.trc"}), 0);
}

TEST(CommandLine, InfoTakesAFileAndJson) {
  const CommandLine c = parsed({"info", "--json", "take.c3d"});
  ASSERT_EQ(c.command, "info");
  EXPECT_EQ(c.info.path, "take.c3d");
  EXPECT_TRUE(c.info.json);
  EXPECT_FALSE(parsed({"info", "take.c3d"}).info.json);
  EXPECT_NE(refused({"info"}), 0);
}

TEST(CommandLine, BuildSubjectTakesTheMeshAndWeightRules) {
  const CommandLine defaults = parsed({"build-subject", "--capture", "rom.c3d", "--out", "s.subject"});
  ASSERT_EQ(defaults.command, "build-subject");
  EXPECT_TRUE(defaults.build_subject.deformation.register_mesh);
  EXPECT_EQ(defaults.build_subject.subject.reference_frame, SubjectBuildOptions{}.reference_frame);
  EXPECT_FALSE(defaults.build_subject.weight_rules.no_joint_split);

  const CommandLine c = parsed({"build-subject", "--capture", "rom.c3d", "--out", "s.subject", "--mesh", "body.obj",
                                "--no-register", "--parts", "12", "--reference-frame", "40", "--no-joint-split",
                                "--boundary-rings", "2", "--part-file", "p.json", "--variance", "0.9"});
  const cli::BuildSubjectOptions& o = c.build_subject;
  EXPECT_EQ(o.mesh_path, "body.obj");
  EXPECT_FALSE(o.deformation.register_mesh);
  EXPECT_EQ(o.deformation.segmentation.target_parts, 12);
  EXPECT_EQ(o.subject.reference_frame, 40);
  EXPECT_EQ(o.subject.pca.variance_kept, 0.9);
  EXPECT_TRUE(o.weight_rules.no_joint_split);
  EXPECT_EQ(o.weight_rules.boundary_rings, 2);
  EXPECT_EQ(o.parts_path, "p.json");
  EXPECT_NE(refused({"build-subject", "--capture", "rom.c3d", "--out", "s", "--variance", "0.2"}), 0);
  EXPECT_NE(refused({"build-subject", "--capture", "rom.c3d", "--out", "s", "--boundary-rings", "-1"}), 0);
}

TEST(CommandLine, EvalDeformTakesTheEvaluationOptions) {
  const CommandLine c = parsed({"eval-deform", "--motions", "breathe", "--seconds", "0.5", "--stride", "2",
                                "--no-fold-blend", "--part-file", "p.json", "--part-file-out", "q.json", "--json"});
  ASSERT_EQ(c.command, "eval-deform");
  const cli::EvalDeformOptions& o = c.eval_deform;
  EXPECT_EQ(o.motions, "breathe");
  EXPECT_EQ(o.seconds, 0.5);
  EXPECT_EQ(o.train_seconds, 20.0);
  EXPECT_EQ(o.evaluation.frame_stride, 2);
  EXPECT_TRUE(o.evaluation.weight_rules.no_fold_blend);
  EXPECT_EQ(o.evaluation.part_file, "p.json");
  EXPECT_EQ(o.parts_out, "q.json");
  EXPECT_TRUE(o.json);
  EXPECT_NE(refused({"eval-deform", "--stride", "0"}), 0);
}

TEST(CommandLine, DeformTakesFormatAndMode) {
  const CommandLine defaults = parsed({"deform", "--subject", "s", "--capture", "c.c3d", "--out", "dir"});
  ASSERT_EQ(defaults.command, "deform");
  EXPECT_EQ(defaults.deform.format, "ply");
  EXPECT_EQ(defaults.deform.mode, "full");
  EXPECT_FALSE(defaults.deform.fill);
  const CommandLine c =
      parsed({"deform", "--subject", "s", "--capture", "c.c3d", "--out", "dir", "--format", "obj", "--mode", "rigid", "--fill", "--no-pc2"});
  EXPECT_EQ(c.deform.format, "obj");
  EXPECT_EQ(c.deform.mode, "rigid");
  EXPECT_TRUE(c.deform.fill);
  EXPECT_TRUE(c.deform.no_pc2);
  EXPECT_NE(refused({"deform", "--subject", "s", "--capture", "c.c3d", "--out", "dir", "--mode", "wobbly"}), 0);
}

}  // namespace
}  // namespace skinstream
