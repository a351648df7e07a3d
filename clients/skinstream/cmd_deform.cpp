#include "clients/skinstream/cmd_deform.h"

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "core/capture_filler.h"
#include "core/deform/mesh_deformer.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/point_cache.h"

namespace skinstream::cli {
namespace {

const std::map<std::string, DeformationMode> kModes = {{"full", DeformationMode::QuadraticRbf},
                                                       {"quadratic", DeformationMode::Quadratic},
                                                       {"rigid-rbf", DeformationMode::RigidRbf},
                                                       {"rigid", DeformationMode::Rigid}};

}  // namespace

int run_deform(const DeformOptions& o, std::FILE* out) {
  if (o.format == "pc2" && o.no_pc2) throw std::invalid_argument("--format pc2 and --no-pc2: nothing would be written");
  const bool per_frame_meshes = o.format == "ply" || o.format == "obj";
  const SubjectFile subject = read_subject_file(o.subject_path);
  if (!subject.deformation)
    throw std::runtime_error(o.subject_path + ": the subject has no detailed mesh; build it with build-subject --mesh");
  const DeformationModel& model = *subject.deformation;
  Capture capture = read_capture(o.capture_path);
  CaptureFillReport report;
  if (o.fill) capture = fill_capture(subject.model, capture, CaptureFillOptions{}, nullptr, &report);
  const std::vector<int> channel = map_channels_to_markers(subject.model, capture, o.fill ? nullptr : &report);
  if (!report.absent_markers.empty())
    throw std::runtime_error(o.capture_path + ": " + std::to_string(report.absent_markers.size()) +
                             " subject markers have no channel, e.g. " + report.absent_markers.front());

  MeshDeformer deformer(model, subject.model, kModes.at(o.mode));
  std::filesystem::create_directories(o.out_dir);
  const std::filesystem::path dir(o.out_dir);
  write_obj((dir / "rest.obj").string(), model.reference_vertices, model.faces);
  std::unique_ptr<PointCacheWriter> cache;
  if (!o.no_pc2)
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
      std::snprintf(name, sizeof name, "frame_%06d.%s", capture.first_frame + f, o.format.c_str());
      if (o.format == "ply")
        write_ply((dir / name).string(), vertices, model.faces);
      else
        write_obj((dir / name).string(), vertices, model.faces, &normals);
    }
    ++written;
  }
  if (cache) cache->close();
  nlohmann::ordered_json summary = {{"frames", written},
                                    {"frames_with_missing_markers", skipped},
                                    {"vertices", model.vertex_count()},
                                    {"parts", model.part_count()},
                                    {"mode", o.mode},
                                    {"out", o.out_dir}};
  std::fprintf(out, "%s\n", summary.dump(2).c_str());
  if (skipped > 0) {
    std::fprintf(stderr, "skinstream deform: %d frames had missing markers and repeat the previous shape; use --fill\n", skipped);
    return 2;
  }
  return 0;
}

}  // namespace skinstream::cli
