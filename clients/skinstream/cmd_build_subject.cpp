// skinstream build-subject: training capture -> subject model file (section 4.1-4.3), and with
// --mesh the detailed mesh registered, segmented and weighted for deformation (section 5.1-5.2).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>
#include <nlohmann/json.hpp>

#include "clients/skinstream/commands.h"
#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "clients/skinstream/weight_rule_flags.h"
#include "core/capture_filler.h"
#include "core/offline/deformation_builder.h"
#include "core/offline/subject_builder.h"
#include "protocol/capture_file.h"
#include "protocol/file_error.h"
#include "protocol/marker_surface_obj.h"
#include "protocol/mesh_file.h"
#include "protocol/subject_file.h"

namespace skinstream::cli {

void add_build_subject(CLI::App& app) {
  auto* cmd = app.add_subcommand("build-subject", "Build the subject model (marker surface, local frames, PCA) from a training capture");
  static std::string capture_path, out_path, surface_in, surface_out, mesh_path, landmarks_path, parts_path, parts_out;
  static SubjectBuildOptions options;
  static DeformationBuildOptions deformation;
  static WeightRuleFlags weight_rules;
  static bool no_register = false;
  cmd->add_option("--capture", capture_path, "training capture (.c3d/.trc), ideally a range-of-motion take")->required();
  cmd->add_option("--out", out_path, "subject file to write")->required();
  cmd->add_option("--reference-frame", options.reference_frame, "frame index of the reference pose (default: chosen)");
  cmd->add_option("--surface", surface_in, "marker surface OBJ to use instead of building one (vertex i = marker i)");
  cmd->add_option("--surface-out", surface_out, "also write the marker surface as OBJ");
  cmd->add_option("--variance", options.pca.variance_kept, "PCA variance kept")->check(CLI::Range(0.5, 1.0))->capture_default_str();
  cmd->add_option("--alpha1", options.parameters.alpha1, "relabel start tolerance (eq. 3)")->capture_default_str();
  cmd->add_option("--alpha2", options.parameters.alpha2, "relabel keep tolerance")->capture_default_str();
  cmd->add_option("--mesh", mesh_path, "detailed mesh (.obj/.ply, mm) in the reference pose: adds the deformation model");
  cmd->add_option("--landmarks", landmarks_path, "JSON {\"marker\": vertex index} for registration (default: guessed)");
  cmd->add_flag("--no-register", no_register, "the mesh is already registered to the marker surface");
  cmd->add_option("--marker-offset", deformation.registration.marker_offset_mm, "markers sit this far above the skin (mm)")
      ->capture_default_str();
  cmd->add_option("--parts", deformation.segmentation.target_parts, "number of near-rigid parts")->capture_default_str();
  add_weight_rule_flags(*cmd, weight_rules);
  cmd->add_option("--part-file", parts_path, "JSON {\"marker\": part index}: your segmentation instead of mean shift");
  cmd->add_option("--part-file-out", parts_out,
                  "also write the segmentation used, in --part-file's form, to adjust by hand and read back");
  cmd->add_option("--bandwidth", deformation.segmentation.bandwidth_degrees, "mean-shift bandwidth (degrees)")
      ->capture_default_str();
  cmd->callback([] {
    // Parts belong to the deformation model: without a mesh they would be silently ignored.
    if (!parts_out.empty() && mesh_path.empty()) throw std::invalid_argument("--part-file-out needs --mesh (parts are made with the mesh)");
    if (!parts_path.empty() && mesh_path.empty()) throw std::invalid_argument("--part-file needs --mesh (parts are made with the mesh)");
    const Capture training = read_capture(capture_path);
    std::vector<std::array<int, 3>> triangles;
    if (!surface_in.empty()) triangles = read_marker_surface_obj(surface_in, static_cast<int>(training.labelled_points().size()));
    SubjectBuildReport report;
    const SubjectModel model = build_subject(training, options, surface_in.empty() ? nullptr : &triangles, &report);
    std::optional<DeformationModel> deformation_model;
    DeformationBuildReport deformation_report;
    if (!mesh_path.empty()) {
      const TriangleMesh mesh = read_mesh(mesh_path);
      // Segmentation and weights need every marker every frame: the take filled by this model.
      const Capture filled = fill_capture(model, training, CaptureFillOptions{});
      const int n = model.marker_count();
      std::vector<Vec3> positions(static_cast<size_t>(filled.frame_count) * n);
      for (int f = 0; f < filled.frame_count; ++f)
        for (int i = 0; i < n; ++i) positions[static_cast<size_t>(f) * n + i] = filled.at(f, i);
      deformation.register_mesh = !no_register;
      apply_weight_rules(weight_rules, deformation);
      if (!landmarks_path.empty()) {
        const std::vector<int> vertex = read_marker_map(landmarks_path, model, "vertex index");
        for (int i = 0; i < n; ++i)
          if (vertex[i] >= 0) {
            if (vertex[i] >= static_cast<int>(mesh.vertices.size()))
              throw FileError(landmarks_path, "vertex " + std::to_string(vertex[i]) + " is beyond the mesh's " +
                                                  std::to_string(mesh.vertices.size()));
            deformation.landmarks.push_back({i, vertex[i]});
          }
      }
      if (!parts_path.empty()) {
        deformation.part_assignment = read_part_file(parts_path, model);
        deformation.assignment_kind = AssignmentKind::PerMarker;
      }
      deformation_model = build_deformation_model(model, positions, filled.frame_count, mesh.vertices, mesh.faces,
                                                  deformation, &deformation_report);
      warn_unused_parts(parts_path, deformation_report.unused_parts);
    }
    write_subject(model, deformation_model ? &*deformation_model : nullptr, out_path);
    if (!parts_out.empty()) write_part_file(parts_out, model, deformation_report.marker_part);
    if (!surface_out.empty())
      write_marker_surface_obj(surface_out, model.marker_names, model.reference_positions, model.triangles);
    nlohmann::ordered_json out = {{"subject", out_path},
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
      out["mesh"] = {{"vertices", deformation_model->vertex_count()},
                     {"faces", deformation_model->face_count()},
                     {"registered", d.registered},
                     {"landmarks", d.landmarks},
                     {"marker_surface_rms_before_mm", d.registration.before.rms},
                     {"marker_surface_rms_after_mm", d.registration.after.rms},
                     {"marker_surface_max_after_mm", d.registration.after.max},
                     {"parts", d.parts},
                     {"mean_shift_groups", d.mean_shift_groups},
                     {"max_part_rigid_rms_mm", d.max_part_rigid_rms_mm},
                     {"part_sizes", part_sizes_json(d, *deformation_model)},
                     {"part_file_unused_parts", d.unused_parts},
                     {"boundary_rings", deformation.weights.boundary_rings},
                     {"boundary_markers", d.boundary_markers},
                     {"mean_parts_per_vertex", d.mean_influences_per_vertex},
                     {"fold_smoothed_vertices", d.fold_smoothed_vertices},
                     {"fold_band_mm", d.fold_band_mm},
                     {"joints", joints_json(d.joints)},
                     {"joint_blend_mm", d.joint_blend_mm},
                     {"part_quadratic_ridges", to_json(d.part_quadratic_ridges)},
                     {"part_rbf_ridges", to_json(d.part_ridges)}};
    }
    std::printf("%s\n", out.dump(2).c_str());
  });
}

}  // namespace skinstream::cli
