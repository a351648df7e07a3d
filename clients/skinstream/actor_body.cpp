#include "clients/skinstream/actor_body.h"

#include <filesystem>

#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/makehuman.h"

namespace skinstream::cli {

bool is_body_template(const std::string& mesh_path) {
  const std::filesystem::path dir = std::filesystem::path(mesh_path).parent_path();
  const MakeHumanFiles files = MakeHumanFiles::in(dir.empty() ? "." : dir.string());
  std::error_code ec;
  return std::filesystem::equivalent(mesh_path, files.body_obj, ec) && std::filesystem::exists(files.skeleton, ec) &&
         std::filesystem::exists(files.weights, ec) && std::filesystem::exists(files.base_obj, ec);
}

ActorBody::ActorBody(const std::string& mesh_path, const MeshFrameOptions& flags, const std::string& template_dir) {
  const TriangleMesh mesh = read_mesh(mesh_path);
  frame_ = detect_mesh_frame(mesh.vertices, mesh.faces, flags);  // refuses what is not a body
  const bool is_template = is_body_template(mesh_path);
  template_ = load_makehuman(is_template ? std::filesystem::path(mesh_path).parent_path().string() : template_dir);
  segments_ = segment_template(template_.skeleton);
  if (is_template) {
    fit_body_ = fit_body_of(template_, segments_);
    return;
  }
  ScanBodyOptions scan_options;
  scan_options.arm_elevation_deg = frame_.side_arm_elevation_deg;  // a T pose's arms start raised
  scan_ =
      skin_scan(template_, segments_, to_skinstream_axes(frame_, mesh.vertices), mesh.faces, scan_options);
  fit_body_ = scan_->body;
}

MarkerPriors ActorBody::priors(std::span<const std::string> labels, std::span<const MarkerSet> sets) const {
  const std::vector<Triangle> template_triangles = triangulate(template_.faces);
  MarkerPriors out = marker_priors(labels, template_, template_triangles, sets);
  if (scan_) out.priors = transfer_priors(out.priors, template_triangles, *scan_);
  return out;
}

}  // namespace skinstream::cli
