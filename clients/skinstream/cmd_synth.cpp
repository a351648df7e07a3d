// skinstream synth: make a synthetic dense-marker capture (Park & Hodgins style, ~350 skin
// markers, 12-camera occlusion, broken trajectories) from the CC0 MakeHuman body, with its truth.
//
//   skinstream synth --motion rom --seconds 20 --seed 7 --markers 350 --out take.c3d
//                    --truth take_truth.c3d [--mesh-out-every 10 meshes/] [--subdivided] [--stats]
//                    [--lookahead L]
//
// The body is read from --body DIR, else $SKINSTREAM_MAKEHUMAN_DIR, else
// $SKINSTREAM_SHARED_DIR/data/meshes/makehuman, else ../shared/data/meshes/makehuman next to the
// source tree the executable was built in (found by walking up from the executable). Meshes are binary PLY,
// DIR/mesh_<frame>.ply (frame index from 0, millimetres, Z up, the same vertex order every frame).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "clients/skinstream/commands.h"
#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/synth_evaluation.h"
#include "core/synth/motion.h"
#include "core/synth/synth_capture.h"
#include "protocol/capture_file.h"
#include "protocol/makehuman.h"
#include "protocol/mesh_ply.h"

namespace skinstream::cli {


void add_synth(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "synth", "Generate a synthetic dense-marker capture with ground truth from the MakeHuman body");
  static synth::SynthOptions options;
  static std::string out, truth_out, body_dir;
  static std::vector<std::string> mesh_out;
  static bool stats = false, no_deform = false;
  static double train_seconds = 20.0;
  static int lookahead = 0;
  static uint64_t seed = 1;
  std::string motions;
  for (const auto& m : synth::motion_names()) motions += (motions.empty() ? "" : ", ") + m;
  cmd->add_option("--motion", options.motion, "motion: " + motions)
      ->check(CLI::IsMember(synth::motion_names()))
      ->capture_default_str();
  cmd->add_option("--seconds", options.seconds, "length of the take in seconds (120 Hz)")
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
  cmd->add_option("--seed", seed, "random seed: the same seed gives the same capture")->capture_default_str();
  cmd->add_option("--markers", options.markers,
                  "number of skin markers (elbow and shoulder-blade extras included)")
      ->check(CLI::Range(11, 5000))
      ->capture_default_str();
  cmd->add_option("--out", out, "broken capture as delivered by the capture system (.c3d or .trc)")
      ->required();
  cmd->add_option("--truth", truth_out, "truth capture: every labelled marker every frame, no noise");
  cmd->add_option("--mesh-out-every", mesh_out,
                  "N DIR: write the truth mesh of every N-th frame as PLY into DIR")
      ->expected(2);
  cmd->add_flag("--subdivided", options.subdivided,
                "markers and meshes on the once-subdivided body (~53,500 vertices)");
  cmd->add_flag("--no-deform", no_deform, "skinning only: no muscle bulge, breathing or jiggle");
  cmd->add_option("--body", body_dir, "folder with the MakeHuman files (default: the shared data folder)");
  cmd->add_flag("--stats", stats,
                "print the counts as JSON, and run skinstream's relabelling and filling on the take against its truth "
                "(subject trained on a range-of-motion take of the same seed)");
  cmd->add_option("--train-seconds", train_seconds, "with --stats: length of the range-of-motion training take")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  cmd->add_option("--lookahead", lookahead, "with --stats: frames of lookahead for the fill (new relabels confirmed over them)")
      ->check(CLI::Range(0, 240))
      ->capture_default_str();
  cmd->callback([] {
    int mesh_every = 0;
    std::string mesh_dir;
    if (!mesh_out.empty()) {
      try {
        mesh_every = std::stoi(mesh_out[0]);
      } catch (const std::exception&) {
        mesh_every = 0;
      }
      if (mesh_every < 1)
        throw std::invalid_argument("--mesh-out-every: N must be a positive integer, got " + mesh_out[0]);
      mesh_dir = mesh_out[1];
    }
    options.seed = seed;
    options.deform = !no_deform;
    const std::string dir = body_dir.empty() ? default_body_dir() : body_dir;
    const auto start = std::chrono::steady_clock::now();
    const synth::Body body = load_makehuman(dir);
    const synth::SynthCapture result = synth::generate(body, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    write_capture(result.capture, out);
    if (!truth_out.empty()) write_capture(result.truth, truth_out);
    int meshes = 0;
    if (mesh_every > 0) {
      std::filesystem::create_directories(mesh_dir);
      for (int f = 0; f < result.frame_count(); f += mesh_every) {
        char name[32];
        std::snprintf(name, sizeof name, "mesh_%06d.ply", f);
        write_ply((std::filesystem::path(mesh_dir) / name).string(), result.pose_mesh(f),
                  result.mesh_faces());
        ++meshes;
      }
    }
    if (stats) {
      nlohmann::ordered_json j;
      j["motion"] = options.motion;
      j["seconds"] = options.seconds;
      j["seed"] = seed;
      j["subdivided"] = options.subdivided;
      j["mesh_vertices"] = result.mesh_vertex_count();
      for (const auto& [key, value] : synth::counts_table(result.counts)) {
        if (key == "occluded_fraction" || key == "missing_fraction")
          j[key] = value;
        else
          j[key] = static_cast<long>(value);
      }
      j["channels"] = result.capture.point_count();
      j["generation_seconds"] = seconds;
      synth::SynthOptions rom = options;
      rom.motion = "rom";
      rom.seconds = train_seconds;
      j["skinstream"] = evaluate_on_synthetic(result, synth::generate(body, rom), lookahead);
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf(
          "wrote %s: %d markers + %d unlabelled channels, %d frames at %.0f Hz, %.1f%% of labelled samples "
          "missing\n",
          out.c_str(), result.counts.markers, result.capture.point_count() - result.counts.markers,
          result.frame_count(), options.rate_hz, 100.0 * result.counts.missing_fraction);
      if (!truth_out.empty()) std::printf("wrote %s: truth\n", truth_out.c_str());
      if (meshes)
        std::printf("wrote %d meshes (%d vertices) to %s\n", meshes, result.mesh_vertex_count(),
                    mesh_dir.c_str());
    }
  });
}

}  // namespace skinstream::cli
