#include "clients/skinstream/command_line.h"

#include <CLI/CLI.hpp>
#include <memory>
#include <stdexcept>
#include <vector>

#include "core/synth/motion.h"

namespace skinstream::cli {
namespace {

// The switches of the weight rules beyond the paper's, spelled the same in build-subject and
// eval-deform.
void add_weight_rule_flags(CLI::App& command, WeightRuleFlags& flags) {
  command.add_flag("--no-joint-split", flags.no_joint_split, "no split of the vertex weights at hinge joints");
  command.add_flag("--no-joint-blend", flags.no_joint_blend,
                   "split at hinge joints with a hard switch at the plane, not a ramp half a marker spacing either side");
  command.add_flag("--no-fold-blend", flags.no_fold_blend,
                   "no blend of the vertex weights across folds (with --no-joint-split: the paper's nearest triangle alone)");
  command.add_flag("--no-fold-smoothing", flags.no_fold_smoothing,
                   "keep the fold blend's vertex weights as they are, not smoothed over the mesh inside folds");
  command
      .add_option("--boundary-rings", flags.boundary_rings,
                  "widen the marker weights' part boundaries by this many rings of the marker surface (0: the paper's)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
}

// A mesh's unit and axes when they should not be detected.
void add_mesh_frame_flags(CLI::App& command, MeshFrameOptions& frame) {
  auto axis = [](const std::string& name) {
    const double sign = name[0] == '-' ? -1.0 : 1.0;
    const char a = name.back();
    return Vec3(a == 'x' ? sign : 0.0, a == 'y' ? sign : 0.0, a == 'z' ? sign : 0.0);
  };
  const std::vector<std::string> axes{"x", "y", "z", "-x", "-y", "-z"};
  command
      .add_option_function<std::string>(
          "--mesh-unit",
          [&frame](const std::string& unit) { frame.unit_mm = unit == "mm" ? 1.0 : unit == "cm" ? 10.0 : unit == "dm" ? 100.0 : 1000.0; },
          "the mesh file's unit (default: detected from its height)")
      ->check(CLI::IsMember({"mm", "cm", "dm", "m"}));
  command.add_option_function<std::string>("--mesh-up", [&frame, axis](const std::string& a) { frame.up = axis(a); },
                                           "the mesh file's up axis (default: detected)")
      ->check(CLI::IsMember(axes));
  command.add_option_function<std::string>("--mesh-forward", [&frame, axis](const std::string& a) { frame.forward = axis(a); },
                                            "the axis the mesh's body faces (default: detected)")
      ->check(CLI::IsMember(axes));
}

void add_info(CLI::App& app, InfoOptions& o) {
  auto* cmd = app.add_subcommand("info", "Print markers, frames, rate, missing fraction and gaps of a C3D/TRC file");
  cmd->add_option("FILE", o.path, "capture (.c3d or .trc)")->required();
  cmd->add_flag("--json", o.json, "machine-readable output");
}

void add_convert(CLI::App& app, ConvertOptions& o) {
  auto* cmd = app.add_subcommand("convert", "Convert a capture between C3D and TRC (format from the extensions)");
  cmd->add_option("IN", o.in_path, "input capture")->required();
  cmd->add_option("OUT", o.out_path, "output capture")->required();
}

void add_build_subject(CLI::App& app, BuildSubjectOptions& o) {
  auto* cmd = app.add_subcommand("build-subject", "Build the subject model (marker surface, local frames, PCA) from a training capture");
  cmd->add_option("--capture", o.capture_path, "training capture (.c3d/.trc), ideally a range-of-motion take")->required();
  cmd->add_option("--out", o.out_path, "subject file to write")->required();
  cmd->add_option("--reference-frame", o.subject.reference_frame, "frame index of the reference pose (default: chosen)");
  cmd->add_option("--surface", o.surface_in, "marker surface OBJ to use instead of building one (vertex i = marker i)");
  cmd->add_option("--surface-out", o.surface_out, "also write the marker surface as OBJ");
  cmd->add_option("--variance", o.subject.pca.variance_kept, "PCA variance kept")->check(CLI::Range(0.5, 1.0))->capture_default_str();
  cmd->add_option("--alpha1", o.subject.parameters.alpha1, "relabel start tolerance (eq. 3)")->capture_default_str();
  cmd->add_option("--alpha2", o.subject.parameters.alpha2, "relabel keep tolerance")->capture_default_str();
  cmd->add_option("--mesh", o.mesh_path,
                  "the body: the template (a MakeHuman body OBJ with its skeleton and weights beside it, fitted to the actor), "
                  "a scan of the actor (.obj/.ply, any pose, unit and axes: fitted through the template), or a mesh "
                  "already in the capture's reference pose and axes; adds the deformation model");
  cmd->add_option("--marker-sets", o.marker_sets_dir, "folder of marker-set definitions (default: the bundled config/marker_sets)");
  cmd->add_option("--marker-height", o.actor.fit.marker_offset_mm, "height of a marker's centre above the skin (mm)")
      ->capture_default_str()->check(CLI::Range(0.0, 100.0));
  cmd->add_option_function<std::string>(
         "--parts-by",
         [&o](const std::string& rule) {
           o.actor.parts = rule == "skeleton" ? PartChoiceRule::Skeleton : rule == "markers" ? PartChoiceRule::Markers : PartChoiceRule::Automatic;
         },
         "the template's parts: skeleton (its segments, for 37-120 markers), markers (mean shift, a dense set), auto")
      ->check(CLI::IsMember({"auto", "skeleton", "markers"}))->default_str("auto");
  add_mesh_frame_flags(*cmd, o.mesh_frame);
  cmd->add_option("--landmarks", o.landmarks_path, "JSON {\"marker\": vertex index} for registration (default: guessed)");
  cmd->add_flag_callback("--no-register", [&o] { o.deformation.register_mesh = false; },
                         "the mesh is already registered to the marker surface");
  cmd->add_option("--marker-offset", o.deformation.registration.marker_offset_mm, "markers sit this far above the skin (mm)")
      ->capture_default_str();
  cmd->add_option("--parts", o.deformation.segmentation.target_parts, "number of near-rigid parts")->capture_default_str();
  add_weight_rule_flags(*cmd, o.weight_rules);
  cmd->add_option("--part-file", o.parts_path, "JSON {\"marker\": part index}: your segmentation instead of mean shift");
  cmd->add_option("--part-file-out", o.parts_out,
                  "also write the segmentation used, in --part-file's form, to adjust by hand and read back");
  cmd->add_option("--bandwidth", o.deformation.segmentation.bandwidth_degrees, "mean-shift bandwidth (degrees)")
      ->capture_default_str();
}

void add_fill(CLI::App& app, FillOptions& o) {
  auto* cmd = app.add_subcommand("fill", "Relabel and fill gaps online (causal by default) and write the filled capture");
  cmd->add_option("--subject", o.subject_path, "subject file from build-subject")->required();
  cmd->add_option("IN", o.in_path, "capture with gaps")->required();
  cmd->add_option("--out", o.out_path, "filled capture to write")->required();
  cmd->add_option("--lookahead", o.fill.lookahead, "frames of lookahead: the gap-end blend, and new relabels confirmed over them (0 = causal)")
      ->check(CLI::Range(0, 240))->capture_default_str();
  cmd->add_option_function<std::string>(
         "--smooth",
         [&o](const std::string& mode) {
           o.fill.smoothing = mode == "online" ? SmoothingMode::Online : mode == "offline" ? SmoothingMode::Offline : SmoothingMode::None;
         },
         "local-frame smoothing: none, online (adds its lookahead), offline")
      ->check(CLI::IsMember({"none", "online", "offline"}))->default_str("none");
  cmd->add_option("--smooth-lookahead", o.fill.smoothing_options.lookahead, "online smoothing lookahead frames")->capture_default_str();
  cmd->add_option("--continuity-seconds", o.fill.filler.continuity_seconds, "gap-start continuity decay (0 = off)")->capture_default_str();
  cmd->add_flag("!--no-pca", o.fill.filler.use_pca, "use only the rigid neighbour estimate (eq. 2)");
}

void add_eval_fill(CLI::App& app, EvalFillOptions& o) {
  auto* cmd = app.add_subcommand("eval-fill", "Measure gap filling against deleted samples, side by side with baselines");
  cmd->add_option("--capture", o.capture_path, "capture with no gaps (truth)")->required();
  cmd->add_option("--train", o.train_path, "training capture of the same subject (default: the first part of --capture)");
  cmd->add_option("--split", o.split, "without --train: train on this fraction of --capture, test on the rest")
      ->check(CLI::Range(0.1, 0.9))->capture_default_str();
  cmd->add_option("--seed", o.gaps.seed, "seed of the gap plan")->capture_default_str();
  cmd->add_option("--gap-protocol", o.gap_protocol,
                  "short: 3 frames to --max-gap-seconds, --gaps-per-minute per marker, each marker on its own; "
                  "long: 2-6 s, three markers at a time, 4% of samples (the other gap options are ignored)")
      ->check(CLI::IsMember({"short", "long"}))->capture_default_str();
  cmd->add_option("--max-gap-seconds", o.gaps.max_seconds, "longest deleted gap")->capture_default_str();
  cmd->add_option("--gaps-per-minute", o.gaps.gaps_per_marker_per_minute, "gaps per marker per minute")->capture_default_str();
  cmd->add_option("--lookahead", o.lookahead, "lookahead frames of the 'skinstream lookahead' row")->capture_default_str();
  cmd->add_flag("--ablations", o.ablations, "also run skinstream without PCA and without gap-start continuity");
  cmd->add_flag("--json", o.json, "JSON only");
}

void add_synth(CLI::App& app, SynthOptions& o) {
  auto* cmd = app.add_subcommand(
      "synth", "Generate a synthetic dense-marker capture with ground truth from the MakeHuman body");
  std::string motions;
  for (const auto& m : synth::motion_names()) motions += (motions.empty() ? "" : ", ") + m;
  cmd->add_option("--motion", o.take.motion, "motion: " + motions)
      ->check(CLI::IsMember(synth::motion_names()))
      ->capture_default_str();
  cmd->add_option("--seconds", o.take.seconds, "length of the take in seconds (120 Hz)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            try {
              const double x = std::stod(v);
              if (x > 0.0 && x <= 3600.0) return {};
            } catch (const std::exception&) {
            }
            return "seconds must be a number in (0, 3600], got " + v;
          },
          "SECONDS"))
      ->capture_default_str();
  cmd->add_option("--seed", o.take.seed, "random seed: the same seed gives the same capture")->capture_default_str();
  cmd->add_option("--markers", o.take.markers,
                  "number of skin markers (elbow and shoulder-blade extras included)")
      ->check(CLI::Range(11, 5000))
      ->capture_default_str();
  cmd->add_option("--out", o.out_path, "broken capture as delivered by the capture system (.c3d or .trc)")
      ->required();
  cmd->add_option("--truth", o.truth_path, "truth capture: every labelled marker every frame, no noise");
  // N and DIR as text, judged once the whole line is parsed (a usage error comes first).
  auto mesh_out = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--mesh-out-every", *mesh_out,
                  "N DIR: write the truth mesh of every N-th frame as PLY into DIR")
      ->expected(2);
  cmd->callback([&o, mesh_out] {
    if (mesh_out->empty()) return;
    int every = 0;
    try {
      every = std::stoi((*mesh_out)[0]);
    } catch (const std::exception&) {
    }
    if (every < 1) throw std::invalid_argument("--mesh-out-every: N must be a positive integer, got " + (*mesh_out)[0]);
    o.mesh_every = every;
    o.mesh_dir = (*mesh_out)[1];
  });
  cmd->add_flag("--subdivided", o.take.subdivided,
                "markers and meshes on the once-subdivided body (~53,500 vertices)");
  cmd->add_flag_callback("--no-deform", [&o] { o.take.deform = false; },
                         "skinning only: no muscle bulge, breathing or jiggle");
  cmd->add_option("--body", o.body_dir, "folder with the MakeHuman files (default: the shared data folder)");
  cmd->add_flag("--stats", o.stats,
                "print the counts as JSON, and run skinstream's relabelling and filling on the take against its truth "
                "(subject trained on a range-of-motion take of the same seed)");
  cmd->add_option("--train-seconds", o.train_seconds, "with --stats: length of the range-of-motion training take")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  cmd->add_option("--lookahead", o.lookahead, "with --stats: frames of lookahead for the fill (new relabels confirmed over them)")
      ->check(CLI::Range(0, 240))
      ->capture_default_str();
}

void add_eval_deform(CLI::App& app, EvalDeformOptions& o) {
  auto* cmd = app.add_subcommand(
      "eval-deform", "Measure the skin deformation (section 5) against synthetic ground truth, methods side by side");
  DeformEvaluationOptions& e = o.evaluation;
  cmd->add_option("--motions", o.motions, "comma-separated motions")->capture_default_str();
  cmd->add_option("--seconds", o.seconds, "length of each evaluated take")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--train-seconds", o.train_seconds, "length of the range-of-motion training take")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o.seed, "seed of the takes (the same body and marker layout)")->capture_default_str();
  cmd->add_flag("--subdivided", o.subdivided, "the once-subdivided body (~53,500 vertices)");
  cmd->add_option("--stride", e.frame_stride, "evaluate every Nth frame")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--covered-reach", e.covered_reach_mm, "vertices within this distance of the marker surface count as covered (mm)")
      ->capture_default_str();
  cmd->add_option("--render", e.render_dir, "write PNGs of a few frames, methods side by side, to this folder");
  cmd->add_option("--body", o.body_dir, "folder with the MakeHuman files (default: the shared data folder)");
  cmd->add_flag("--deform-registered", e.deform_registered_mesh,
                "deform the registered artist's model instead of the reference frame's truth skin");
  add_weight_rule_flags(*cmd, e.weight_rules);
  cmd->add_option("--part-file", e.part_file,
                  "JSON {\"marker\": part index}: your segmentation instead of mean shift (build-subject --part-file-out writes one)");
  cmd->add_option("--part-file-out", o.parts_out, "also write the segmentation used, in --part-file's form");
  cmd->add_flag("--json", o.json, "JSON only");
}

void add_deform(CLI::App& app, DeformOptions& o) {
  auto* cmd = app.add_subcommand("deform", "Deform the subject's detailed mesh by a filled capture (section 5.3)");
  cmd->add_option("--subject", o.subject_path, "subject file built with build-subject --mesh")->required();
  cmd->add_option("--capture", o.capture_path, "filled capture (.c3d/.trc); see --fill")->required();
  cmd->add_option("--out", o.out_dir, "output folder")->required();
  cmd->add_option("--format", o.format, "per-frame meshes: ply or obj; pc2 or none: the point cache only")
      ->check(CLI::IsMember({"ply", "obj", "pc2", "none"}))->capture_default_str();
  cmd->add_option("--mode", o.mode, "full (quadratic + RBF), quadratic, rigid-rbf or rigid")
      ->check(CLI::IsMember({"full", "quadratic", "rigid-rbf", "rigid"}))->capture_default_str();
  cmd->add_flag("--fill", o.fill, "relabel and fill the capture online first (as the daemon does)");
  cmd->add_flag("--no-pc2", o.no_pc2, "do not write the point cache");
}

void add_eval_actor(CLI::App& app, EvalActorOptions& o) {
  auto* cmd = app.add_subcommand(
      "eval-actor", "Measure a real actor's subject on markers it was not given: held-out markers, folds, methods side by side");
  cmd->add_option("--capture", o.capture_path, "a real take with named markers (.c3d/.trc)")->required();
  cmd->add_option("--mesh", o.mesh_path, "the body template's OBJ (its skeleton and weights beside it) or a scan (default: the bundled template)");
  add_mesh_frame_flags(*cmd, o.mesh_frame);
  cmd->add_option("--marker-sets", o.marker_sets_dir, "folder of marker-set definitions (default: the bundled ones)");
  cmd->add_option("--withhold", o.withhold, "markers withheld per fold")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--split", o.split, "train on this fraction of the take, test on the rest")
      ->check(CLI::Range(0.1, 0.9))->capture_default_str();
  cmd->add_option("--stride", o.stride, "test every Nth frame")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--folds", o.max_folds, "at most this many folds (0: every marker withheld once)")->capture_default_str();
  cmd->add_option("--marker-height", o.build.fit.marker_offset_mm, "height of a marker's centre above the skin (mm)")
      ->capture_default_str()->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--seed", o.seed, "seed of the folds' marker order")->capture_default_str();
  cmd->add_option("--render", o.render_dir, "write PNGs of the first fold (reference pose, a few test frames) to this folder");
  cmd->add_flag("--json", o.json, "JSON only");
}

}  // namespace

std::optional<int> parse_command_line(int argc, const char* const* argv, CommandLine& out) {
  CLI::App app{"skinstream: dense marker capture to deforming skin (Park & Hodgins 2006)"};
  app.require_subcommand(1);
  add_info(app, out.info);
  add_convert(app, out.convert);
  add_build_subject(app, out.build_subject);
  add_fill(app, out.fill);
  add_eval_fill(app, out.eval_fill);
  add_synth(app, out.synth);
  add_eval_deform(app, out.eval_deform);
  add_deform(app, out.deform);
  add_eval_actor(app, out.eval_actor);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  out.command = app.get_subcommands().front()->get_name();
  return std::nullopt;
}

}  // namespace skinstream::cli
