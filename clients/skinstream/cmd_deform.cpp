// skinstream deform: a filled capture -> the deforming detailed mesh (section 5.3), as the daemon
// computes it per frame, written as per-frame meshes and a point cache.
//   skinstream deform --subject S.sksubj --capture FILLED.c3d --out DIR [--format ply|obj|pc2|none]
//                     [--mode full|quadratic|rigid-rbf|rigid] [--fill] [--no-pc2]
// Writes DIR/frame_<frame number, 6 digits>.<format> for ply and obj (frame number = the
// capture's first frame + index, as the replay server numbers frames), DIR/deformed.pc2 (every
// frame; --format pc2 or none: the point cache alone) and DIR/rest.obj (the registered
// reference mesh whose vertex order the point cache follows).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "clients/skinstream/commands.h"
#include "core/capture_filler.h"
#include "core/deform/mesh_deformer.h"
#include "protocol/capture_file.h"
#include "protocol/mesh_file.h"
#include "protocol/point_cache.h"
#include "protocol/subject_file.h"

namespace skinstream::cli {

namespace {

const std::map<std::string, DeformationMode> kModes = {{"full", DeformationMode::QuadraticRbf},
                                                       {"quadratic", DeformationMode::Quadratic},
                                                       {"rigid-rbf", DeformationMode::RigidRbf},
                                                       {"rigid", DeformationMode::Rigid}};

}  // namespace

void add_deform(CLI::App& app) {
  auto* cmd = app.add_subcommand("deform", "Deform the subject's detailed mesh by a filled capture (section 5.3)");
  static std::string subject_path, capture_path, out_dir, format = "ply", mode = "full";
  static bool fill = false, no_pc2 = false;
  cmd->add_option("--subject", subject_path, "subject file built with build-subject --mesh")->required();
  cmd->add_option("--capture", capture_path, "filled capture (.c3d/.trc); see --fill")->required();
  cmd->add_option("--out", out_dir, "output folder")->required();
  cmd->add_option("--format", format, "per-frame meshes: ply or obj; pc2 or none: the point cache only")
      ->check(CLI::IsMember({"ply", "obj", "pc2", "none"}))->capture_default_str();
  cmd->add_option("--mode", mode, "full (quadratic + RBF), quadratic, rigid-rbf or rigid")
      ->check(CLI::IsMember({"full", "quadratic", "rigid-rbf", "rigid"}))->capture_default_str();
  cmd->add_flag("--fill", fill, "relabel and fill the capture online first (as the daemon does)");
  cmd->add_flag("--no-pc2", no_pc2, "do not write the point cache");
  cmd->callback([] {
    if (format == "pc2" && no_pc2) throw std::invalid_argument("--format pc2 and --no-pc2: nothing would be written");
    const bool per_frame_meshes = format == "ply" || format == "obj";
    const SubjectFile subject = read_subject_file(subject_path);
    if (!subject.deformation)
      throw std::runtime_error(subject_path + ": the subject has no detailed mesh; build it with build-subject --mesh");
    const DeformationModel& model = *subject.deformation;
    Capture capture = read_capture(capture_path);
    CaptureFillReport report;
    if (fill) capture = fill_capture(subject.model, capture, CaptureFillOptions{}, nullptr, &report);
    const std::vector<int> channel = map_channels_to_markers(subject.model, capture, fill ? nullptr : &report);
    if (!report.absent_markers.empty())
      throw std::runtime_error(capture_path + ": " + std::to_string(report.absent_markers.size()) +
                               " subject markers have no channel, e.g. " + report.absent_markers.front());

    MeshDeformer deformer(model, subject.model, kModes.at(mode));
    std::filesystem::create_directories(out_dir);
    const std::filesystem::path dir(out_dir);
    write_obj((dir / "rest.obj").string(), model.reference_vertices, model.faces);
    std::unique_ptr<PointCacheWriter> cache;
    if (!no_pc2)
      cache = std::make_unique<PointCacheWriter>((dir / "deformed.pc2").string(), model.vertex_count(),
                                                 static_cast<float>(capture.first_frame));

    const int n = subject.model.marker_count();
    std::vector<Vec3> markers(n), vertices(model.vertex_count()), normals(model.vertex_count());
    std::vector<float> positions(static_cast<size_t>(model.vertex_count()) * 3), normal_buffer(positions.size());
    int written = 0, skipped = 0;
    for (int f = 0; f < capture.frame_count; ++f) {
      for (int i = 0; i < n; ++i) markers[i] = capture.at(f, channel[i]);
      // A marker missing: deform() leaves the buffers alone, so the previous frame's shape is
      // written again.
      if (!deformer.deform(markers, positions, normal_buffer)) ++skipped;
      for (int v = 0; v < model.vertex_count(); ++v) {
        vertices[v] = Vec3(positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]);
        normals[v] = Vec3(normal_buffer[v * 3], normal_buffer[v * 3 + 1], normal_buffer[v * 3 + 2]);
      }
      if (cache) cache->append(vertices);
      if (per_frame_meshes) {
        char name[48];
        std::snprintf(name, sizeof name, "frame_%06d.%s", capture.first_frame + f, format.c_str());
        if (format == "ply")
          write_ply((dir / name).string(), vertices, model.faces);
        else
          write_obj((dir / name).string(), vertices, model.faces, &normals);
      }
      ++written;
    }
    if (cache) cache->close();
    nlohmann::ordered_json out = {{"frames", written},
                                  {"frames_with_missing_markers", skipped},
                                  {"vertices", model.vertex_count()},
                                  {"parts", model.part_count()},
                                  {"mode", mode},
                                  {"out", out_dir}};
    std::printf("%s\n", out.dump(2).c_str());
    if (skipped > 0) {
      std::fprintf(stderr, "skinstream deform: %d frames had missing markers and repeat the previous shape; use --fill\n", skipped);
      exit_code = 2;
    }
  });
}

}  // namespace skinstream::cli
