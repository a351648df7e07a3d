#include "clients/skinstream/cmd_synth.h"

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/synth_evaluation.h"
#include "protocol/files/capture_file.h"
#include "protocol/meshes/mesh_ply.h"
#include "protocol/offline/makehuman.h"

namespace skinstream::cli {

int run_synth(const SynthOptions& o, std::FILE* out) {
  const synth::SynthOptions& take = o.take;
  const auto start = std::chrono::steady_clock::now();
  const Body body = load_makehuman(o.body_dir.empty() ? default_body_dir() : o.body_dir);
  const synth::SynthCapture result = synth::generate(body, take);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  write_capture(result.capture, o.out_path);
  if (!o.truth_path.empty()) write_capture(result.truth, o.truth_path);
  int meshes = 0;
  if (o.mesh_every > 0) {
    std::filesystem::create_directories(o.mesh_dir);
    for (int f = 0; f < result.frame_count(); f += o.mesh_every) {
      char name[32];
      std::snprintf(name, sizeof name, "mesh_%06d.ply", f);
      write_ply((std::filesystem::path(o.mesh_dir) / name).string(), result.pose_mesh(f), result.mesh_faces());
      ++meshes;
    }
  }
  if (o.stats) {
    nlohmann::ordered_json j;
    j["motion"] = take.motion;
    j["seconds"] = take.seconds;
    j["seed"] = take.seed;
    j["subdivided"] = take.subdivided;
    j["mesh_vertices"] = result.mesh_vertex_count();
    for (const auto& [key, value] : synth::counts_table(result.counts)) {
      if (key == "occluded_fraction" || key == "missing_fraction")
        j[key] = value;
      else
        j[key] = static_cast<long>(value);
    }
    j["channels"] = result.capture.point_count();
    j["generation_seconds"] = seconds;
    synth::SynthOptions rom = take;
    rom.motion = "rom";
    rom.seconds = o.train_seconds;
    j["skinstream"] = evaluate_on_synthetic(result, synth::generate(body, rom), o.lookahead);
    std::fprintf(out, "%s\n", j.dump(2).c_str());
    return 0;
  }
  std::fprintf(out,
               "wrote %s: %d markers + %d unlabelled channels, %d frames at %.0f Hz, %.1f%% of labelled samples "
               "missing\n",
               o.out_path.c_str(), result.counts.markers, result.capture.point_count() - result.counts.markers,
               result.frame_count(), take.rate_hz, 100.0 * result.counts.missing_fraction);
  if (!o.truth_path.empty()) std::fprintf(out, "wrote %s: truth\n", o.truth_path.c_str());
  if (meshes)
    std::fprintf(out, "wrote %d meshes (%d vertices) to %s\n", meshes, result.mesh_vertex_count(), o.mesh_dir.c_str());
  return 0;
}

}  // namespace skinstream::cli
