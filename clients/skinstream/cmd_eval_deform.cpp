// skinstream eval-deform: section 5 against the synthetic ground truth, every method side by
// side (rigid, quadratic, rigid + RBF, the full method, and sparse-marker linear blend skinning).
//   skinstream eval-deform [--motions breathe,flex,...] [--seconds 5] [--seed 1] [--subdivided]
//                          [--stride 4] [--render DIR] [--part-file P.json] [--part-file-out P.json] [--json]
#include <CLI/CLI.hpp>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "clients/skinstream/commands.h"
#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/deform_evaluation.h"
#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "core/synth/synth_capture.h"
#include "core/synth/subdivision.h"
#include "protocol/makehuman.h"

namespace skinstream::cli {

namespace {

std::vector<std::string> split_list(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

void print_table(const nlohmann::ordered_json& result) {
  std::printf("| motion | method | vertex mean mm | vertex p95 mm | vertex max mm | all vertices mean mm | marker mean mm | marker max mm |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const auto& take : result["takes"])
    for (const auto& row : take["methods"])
      std::printf("| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", take["motion"].get<std::string>().c_str(),
                  row["method"].get<std::string>().c_str(), row["vertex_mean_mm"].get<double>(),
                  row["vertex_p95_mm"].get<double>(), row["vertex_max_mm"].get<double>(),
                  row["all_vertex_mean_mm"].get<double>(),
                  row["marker_mean_mm"].get<double>(), row["marker_max_mm"].get<double>());
}

}  // namespace

void add_eval_deform(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "eval-deform", "Measure the skin deformation (section 5) against synthetic ground truth, methods side by side");
  static std::string motions = "breathe,flex,golf,punch,jumprope", body_dir;
  static double seconds = 5.0, train_seconds = 20.0;
  static uint64_t seed = 1;
  static bool subdivided = false, json = false;
  static DeformEvaluationOptions options;
  cmd->add_option("--motions", motions, "comma-separated motions")->capture_default_str();
  cmd->add_option("--seconds", seconds, "length of each evaluated take")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--train-seconds", train_seconds, "length of the range-of-motion training take")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--seed", seed, "seed of the takes (the same body and marker layout)")->capture_default_str();
  cmd->add_flag("--subdivided", subdivided, "the once-subdivided body (~53,500 vertices)");
  cmd->add_option("--stride", options.frame_stride, "evaluate every Nth frame")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--covered-reach", options.covered_reach_mm, "vertices within this distance of the marker surface count as covered (mm)")
      ->capture_default_str();
  cmd->add_option("--render", options.render_dir, "write PNGs of a few frames, methods side by side, to this folder");
  cmd->add_option("--body", body_dir, "folder with the MakeHuman files (default: the shared data folder)");
  cmd->add_flag("--deform-registered", options.deform_registered_mesh,
                "deform the registered artist's model instead of the reference frame's truth skin");
  add_weight_rule_flags(*cmd, options.weight_rules);
  cmd->add_option("--part-file", options.part_file,
                  "JSON {\"marker\": part index}: your segmentation instead of mean shift (build-subject --part-file-out writes one)");
  static std::string parts_out;
  cmd->add_option("--part-file-out", parts_out, "also write the segmentation used, in --part-file's form");
  cmd->add_flag("--json", json, "JSON only");
  cmd->callback([] {
    const synth::Body body = load_makehuman(body_dir.empty() ? default_body_dir() : body_dir);
    synth::SynthOptions rom;
    rom.motion = "rom";
    rom.seconds = train_seconds;
    rom.seed = seed;
    rom.subdivided = subdivided;
    const synth::SynthCapture training = synth::generate(body, rom);
    const DeformationSetup setup = prepare_deformation(body, training, options);
    warn_unused_parts(options.part_file, setup.build.unused_parts);
    if (!parts_out.empty()) write_part_file(parts_out, setup.subject, setup.build.marker_part);

    nlohmann::ordered_json result;
    result["seed"] = seed;
    result["subdivided"] = subdivided;
    result["vertices"] = setup.deformation.vertex_count();
    result["markers"] = setup.subject.marker_count();
    result["parts"] = setup.build.parts;
    result["conventional_markers"] = setup.conventional.marker_count();
    result["registration"] = {{"landmarks", setup.subject.marker_count()},
                              {"marker_surface_rms_before_mm", setup.registration.before.rms},
                              {"marker_surface_rms_after_mm", setup.registration.after.rms},
                              {"marker_surface_max_after_mm", setup.registration.after.max},
                              {"vertex_error_vs_truth_mm", setup.registration_vertex_error_mm},
                              {"iterations", setup.registration.iterations},
                              {"used_for_deformation", options.deform_registered_mesh}};
    result["max_part_rigid_rms_mm"] = setup.build.max_part_rigid_rms_mm;
    result["part_sizes"] = part_sizes_json(setup.build, setup.deformation);
    result["part_file_unused_parts"] = setup.build.unused_parts;
    result["boundary_rings"] = options.weight_rules.boundary_rings;
    result["boundary_markers"] = setup.build.boundary_markers;
    result["mean_parts_per_vertex"] = setup.build.mean_influences_per_vertex;
    result["fold_smoothed_vertices"] = setup.build.fold_smoothed_vertices;
    result["fold_band_mm"] = setup.build.fold_band_mm;
    result["joints"] = joints_json(setup.build.joints);
    result["joint_blend_mm"] = setup.build.joint_blend_mm;
    result["part_quadratic_ridges"] = to_json(setup.build.part_quadratic_ridges);
    result["part_rbf_ridges"] = to_json(setup.build.part_ridges);
    result["build_seconds"] = setup.build_seconds;
    result["takes"] = nlohmann::ordered_json::array();
    for (const std::string& motion : split_list(motions)) {
      synth::SynthOptions take_options = rom;
      take_options.motion = motion;
      take_options.seconds = seconds;
      const synth::SynthCapture take = synth::generate(body, take_options);
      result["takes"].push_back(evaluate_deformation(setup, take, motion, options));
      if (!json) std::fprintf(stderr, "eval-deform: %s done\n", motion.c_str());
    }
    result["table_rule"] = judge_table_rule(result["takes"]);
    if (json) {
      std::printf("%s\n", result.dump(2).c_str());
    } else {
      std::printf("%s\n", result.dump(2).c_str());
      print_table(result);
    }
  });
}

}  // namespace skinstream::cli
