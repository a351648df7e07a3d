#include "clients/skinstream/cmd_eval_deform.h"

#include <nlohmann/json.hpp>
#include <sstream>

#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "core/synth/synth_capture.h"
#include "protocol/offline/makehuman.h"

namespace skinstream::cli {
namespace {

std::vector<std::string> split_list(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

void print_table(const nlohmann::ordered_json& result, std::FILE* out) {
  std::fprintf(out, "| motion | method | vertex mean mm | vertex p95 mm | vertex max mm | all vertices mean mm | marker mean mm | marker max mm |\n");
  std::fprintf(out, "|---|---|---|---|---|---|---|---|\n");
  for (const auto& take : result["takes"])
    for (const auto& row : take["methods"])
      std::fprintf(out, "| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", take["motion"].get<std::string>().c_str(),
                   row["method"].get<std::string>().c_str(), row["vertex_mean_mm"].get<double>(),
                   row["vertex_p95_mm"].get<double>(), row["vertex_max_mm"].get<double>(),
                   row["all_vertex_mean_mm"].get<double>(),
                   row["marker_mean_mm"].get<double>(), row["marker_max_mm"].get<double>());
}

}  // namespace

int run_eval_deform(const EvalDeformOptions& o, std::FILE* out) {
  const Body body = load_makehuman(o.body_dir.empty() ? default_body_dir() : o.body_dir);
  synth::SynthOptions rom;
  rom.motion = "rom";
  rom.seconds = o.train_seconds;
  rom.seed = o.seed;
  rom.subdivided = o.subdivided;
  const synth::SynthCapture training = synth::generate(body, rom);
  const DeformationSetup setup = prepare_deformation(body, training, o.evaluation);
  warn_unused_parts(o.evaluation.part_file, setup.build.unused_parts);
  if (!o.parts_out.empty()) write_part_file(o.parts_out, setup.subject, setup.build.marker_part);

  nlohmann::ordered_json result;
  result["seed"] = o.seed;
  result["subdivided"] = o.subdivided;
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
                            {"used_for_deformation", o.evaluation.deform_registered_mesh}};
  add_parts_and_weights_json(result, setup.build, setup.deformation, o.evaluation.weight_rules.boundary_rings);
  result["build_seconds"] = setup.build_seconds;
  result["takes"] = nlohmann::ordered_json::array();
  for (const std::string& motion : split_list(o.motions)) {
    synth::SynthOptions take_options = rom;
    take_options.motion = motion;
    take_options.seconds = o.seconds;
    const synth::SynthCapture take = synth::generate(body, take_options);
    result["takes"].push_back(evaluate_deformation(setup, take, motion, o.evaluation));
    if (!o.json) std::fprintf(stderr, "eval-deform: %s done\n", motion.c_str());
  }
  result["table_rule"] = judge_table_rule(result["takes"]);
  std::fprintf(out, "%s\n", result.dump(2).c_str());
  if (!o.json) print_table(result, out);
  return 0;
}

}  // namespace skinstream::cli
