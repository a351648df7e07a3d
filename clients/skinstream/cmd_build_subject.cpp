#include "clients/skinstream/cmd_build_subject.h"

#include <optional>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "core/capture_filler.h"
#include "protocol/capture_file.h"
#include "protocol/file_error.h"
#include "protocol/marker_surface_obj.h"
#include "protocol/mesh_file.h"
#include "protocol/subject_file.h"

namespace skinstream::cli {

int run_build_subject(const BuildSubjectOptions& o, std::FILE* out) {
  DeformationBuildOptions deformation = o.deformation;
  // Parts belong to the deformation model: without a mesh they would be silently ignored.
  if (!o.parts_out.empty() && o.mesh_path.empty()) throw std::invalid_argument("--part-file-out needs --mesh (parts are made with the mesh)");
  if (!o.parts_path.empty() && o.mesh_path.empty()) throw std::invalid_argument("--part-file needs --mesh (parts are made with the mesh)");
  const Capture training = read_capture(o.capture_path);
  std::vector<std::array<int, 3>> triangles;
  if (!o.surface_in.empty()) triangles = read_marker_surface_obj(o.surface_in, static_cast<int>(training.labelled_points().size()));
  SubjectBuildReport report;
  const SubjectModel model = build_subject(training, o.subject, o.surface_in.empty() ? nullptr : &triangles, &report);
  std::optional<DeformationModel> deformation_model;
  DeformationBuildReport deformation_report;
  if (!o.mesh_path.empty()) {
    const TriangleMesh mesh = read_mesh(o.mesh_path);
    // Segmentation and weights need every marker every frame: the take filled by this model.
    const Capture filled = fill_capture(model, training, CaptureFillOptions{});
    const int n = model.marker_count();
    std::vector<Vec3> positions(static_cast<size_t>(filled.frame_count) * n);
    for (int f = 0; f < filled.frame_count; ++f)
      for (int i = 0; i < n; ++i) positions[static_cast<size_t>(f) * n + i] = filled.at(f, i);
    apply_weight_rules(o.weight_rules, deformation);
    if (!o.landmarks_path.empty()) {
      const std::vector<int> vertex = read_marker_map(o.landmarks_path, model, "vertex index");
      for (int i = 0; i < n; ++i)
        if (vertex[i] >= 0) {
          if (vertex[i] >= static_cast<int>(mesh.vertices.size()))
            throw FileError(o.landmarks_path, "vertex " + std::to_string(vertex[i]) + " is beyond the mesh's " +
                                                std::to_string(mesh.vertices.size()));
          deformation.landmarks.push_back({i, vertex[i]});
        }
    }
    if (!o.parts_path.empty()) {
      deformation.part_assignment = read_part_file(o.parts_path, model);
      deformation.assignment_kind = AssignmentKind::PerMarker;
    }
    deformation_model = build_deformation_model(model, positions, filled.frame_count, mesh.vertices, mesh.faces,
                                                deformation, &deformation_report);
    warn_unused_parts(o.parts_path, deformation_report.unused_parts);
  }
  write_subject(model, deformation_model ? &*deformation_model : nullptr, o.out_path);
  if (!o.parts_out.empty()) write_part_file(o.parts_out, model, deformation_report.marker_part);
  if (!o.surface_out.empty())
    write_marker_surface_obj(o.surface_out, model.marker_names, model.reference_positions, model.triangles);
  nlohmann::ordered_json report_json = {{"subject", o.out_path},
                                        {"markers", report.markers},
                                        {"reference_frame", report.reference_frame},
                                        {"triangles", report.triangles},
                                        {"mean_ring_size", report.mean_ring_size},
                                        {"markers_given_extra_neighbours", report.markers_given_extra_neighbours},
                                        {"mean_pca_components", report.mean_pca_components},
                                        {"min_training_frames", report.min_training_frames},
                                        {"markers_never_complete", report.markers_never_complete}};
  if (deformation_model) {
    const DeformationBuildReport& d = deformation_report;
    nlohmann::ordered_json mesh = {{"vertices", deformation_model->vertex_count()},
                                   {"faces", deformation_model->face_count()},
                                   {"registered", d.registered},
                                   {"landmarks", d.landmarks},
                                   {"marker_surface_rms_before_mm", d.registration.before.rms},
                                   {"marker_surface_rms_after_mm", d.registration.after.rms},
                                   {"marker_surface_max_after_mm", d.registration.after.max},
                                   {"parts", d.parts},
                                   {"mean_shift_groups", d.mean_shift_groups}};
    add_parts_and_weights_json(mesh, d, *deformation_model, deformation.weights.boundary_rings);
    report_json["mesh"] = mesh;
  }
  std::fprintf(out, "%s\n", report_json.dump(2).c_str());
  return 0;
}

}  // namespace skinstream::cli
