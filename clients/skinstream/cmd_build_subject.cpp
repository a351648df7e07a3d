#include "clients/skinstream/cmd_build_subject.h"

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "clients/skinstream/actor_body.h"
#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "core/capture_filler.h"
#include "core/fitting/marker_priors.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/file_error.h"
#include "protocol/files/subject_file.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/makehuman.h"
#include "protocol/offline/marker_set_file.h"
#include "protocol/offline/marker_surface_obj.h"

namespace skinstream::cli {

namespace {

nlohmann::ordered_json surface_json(const SurfaceCheck& c) {
  return {{"strained_fraction", c.strained_fraction},
          {"max_strain", c.max_strain},
          {"longest_stretched_edge", c.longest_stretched_edge},
          {"flipped_triangles", c.flipped_triangles},
          {"self_intersecting_triangles", c.self_intersecting_triangles},
          {"problem", c.problem}};
}

nlohmann::ordered_json actor_json(const ActorSubject& s, const MarkerPriors& priors, const TemplateSegments& segments) {
  const ActorFit& fit = s.fit;
  nlohmann::ordered_json markers = nlohmann::ordered_json::object();
  for (int i = 0; i < s.model.marker_count(); ++i)
    markers[s.model.marker_names[i]] = {{"named", priors.priors[i].place.triangle >= 0 || !priors.priors[i].allowed_triangles.empty()},
                                        {"fit_rms_mm", fit.marker_rms_mm[i]},
                                        {"height_mm", fit.attachments[i].offset_mm}};
  nlohmann::ordered_json proportions = {{"overall", fit.proportions.overall}};
  for (size_t g = 0; g < fit.proportions.length.size(); ++g)
    proportions[segments.shape_groups[g]] = {{"length", fit.proportions.length[g]}, {"girth", fit.proportions.girth[g]}};
  nlohmann::ordered_json lengths = nlohmann::ordered_json::object();
  for (const SegmentLength& l : s.check.lengths) lengths[l.name] = {{"mm", l.mm}, {"human_range_mm", {l.low_mm, l.high_mm}}};
  nlohmann::ordered_json parts = nlohmann::ordered_json::array();
  for (const PartChoice& p : s.skeletal_report.parts)
    parts.push_back({{"part", p.name}, {"members", p.members}, {"terms", p.why}, {"quadratic_ridge", p.quadratic_ridge},
                     {"rbf_ridge", p.rbf_ridge}});
  return {{"marker_set", priors.set_name},
          {"marker_set_match", priors.description},
          {"articulation_mm", s.motion.articulation_mm},
          {"blind_start", fit.blind},
          {"fit_frames", fit.frames.size()},
          {"tracked_frames", fit.tracked_frames},
          {"fit_rms_mm", fit.rms_mm},
          {"height_mm", s.check.height_mm},
          {"proportions", proportions},
          {"segment_lengths", lengths},
          {"parts_by", s.skeleton_parts ? "skeleton segments (sparse marker set)"
                                        : "mean shift on the marker surface (dense set)"},
          {"parts", parts},
          {"skeleton_rms_mm", s.skeletal_report.skeleton_rms_mm},
          {"checks",
           {{"plausible", s.check.ok()},
            {"problem", s.check.problem},
            {"registration", surface_json(s.check.registration)},
            {"reference_pose", surface_json(s.check.pose)},
            {"take_frames_checked", s.check.take_frames_checked},
            {"worst_take_frame", s.check.worst_take_frame_index},
            {"worst_take_frame_surface", surface_json(s.check.worst_take_frame)},
            {"take_longest_stretched_edge",
             {{"typical_edges", s.check.take_longest_stretched_edge},
              {"frame", s.check.take_longest_stretched_edge_frame},
              {"limit", s.check.take_edge_stretch_limit}}},
            {"unplaced_markers", s.check.unplaced_markers}}},
          {"markers", markers},
          {"seconds", {{"fit", s.fit_seconds}, {"build", s.build_seconds}, {"checks", s.check_seconds}}}};
}

// The actor path: the template, or a scan through it, fitted to the markers, checked.
int build_actor(const BuildSubjectOptions& o, const Capture& training, std::FILE* out) {
  const ActorBody body(o.mesh_path, o.mesh_frame, default_body_dir());
  const std::vector<MarkerSet> sets = read_marker_sets(o.marker_sets_dir.empty() ? default_marker_sets_dir() : o.marker_sets_dir);
  std::vector<std::string> labels;
  for (int c : training.labelled_points()) labels.push_back(training.labels[c]);
  const MarkerPriors priors = body.priors(labels, sets);
  ActorSubjectOptions options = o.actor;
  options.subject = o.subject;
  const ActorSubject s = build_actor_subject(training, body.fit_body(), priors.priors, options);
  if (!s.check.ok()) throw std::invalid_argument("refused, nothing written: " + s.check.problem);
  write_subject(s.model, &s.deformation, o.out_path);
  if (!o.surface_out.empty()) write_marker_surface_obj(o.surface_out, s.model.marker_names, s.model.reference_positions, s.model.triangles);
  nlohmann::ordered_json report = {{"subject", o.out_path},
                                   {"markers", s.subject_report.markers},
                                   {"reference_frame", s.subject_report.reference_frame},
                                   {"triangles", s.subject_report.triangles},
                                   {"mean_pca_components", s.subject_report.mean_pca_components},
                                   {"markers_never_complete", s.subject_report.markers_never_complete}};
  nlohmann::ordered_json scan;
  if (const ScanBody* sb = body.scan())
    scan = {{"unit_mm", body.frame().unit_mm},
            {"height_mm", body.frame().height_mm},
            {"arm_elevation_deg", body.frame().arm_elevation_deg},
            {"template_fit_rms_mm", sb->fit_rms_mm},
            {"template_registered_rms_mm", sb->registered_rms_mm},
            {"scan_to_template_median_mm", sb->inherited_median_mm},
            {"scan_to_template_max_mm", sb->inherited_max_mm}};
  report["mesh"] = {{body.is_scan() ? "scan" : "template", o.mesh_path},
                    {"through_the_template", scan},
                    {"vertices", s.deformation.vertex_count()},
                    {"faces", s.deformation.face_count()},
                    {"registered", s.skeletal_report.registered},
                    {"registration_skipped", s.registration_skipped},
                    {"marker_skin_rms_after_mm", s.skeletal_report.registration.after.rms},
                    {"landmark_rms_after_mm", s.skeletal_report.registration.landmark_rms_after_mm}};
  report["actor"] = actor_json(s, priors, body.segments());
  std::fprintf(out, "%s\n", report.dump(2).c_str());
  return 0;
}

// A mesh made in the capture's own reference pose and axes (the same subject, e.g. the synthetic
// demo's): a body in millimetres, Z up, with the markers of the reference frame on its skin. Any
// other mesh (the template, a scan in its own pose and axes) goes through the actor fit.
bool in_capture_frame(const BuildSubjectOptions& o, const Capture& training) {
  if (is_body_template(o.mesh_path)) return false;
  const TriangleMesh mesh = read_mesh(o.mesh_path);
  const MeshFrame frame = detect_mesh_frame(mesh.vertices, mesh.faces, o.mesh_frame);  // refuses what is not a body
  const bool z_up = (frame.rotation.transpose() * Vec3::UnitZ() - Vec3::UnitZ()).norm() < 1e-6;
  if (frame.unit_mm != 1.0 || !z_up) return false;
  const std::vector<int> channels = training.labelled_points();
  const int reference = o.subject.reference_frame >= 0 ? o.subject.reference_frame : choose_reference_frame(training, channels);
  if (reference < 0 || reference >= training.frame_count) return false;
  std::vector<Vec3> markers;
  for (int c : channels) markers.push_back(training.at(reference, c));
  return marker_surface_distance(mesh.vertices, mesh.faces, markers).mean <= 40.0;
}

}  // namespace

int run_build_subject(const BuildSubjectOptions& o, std::FILE* out) {
  DeformationBuildOptions deformation = o.deformation;
  // Parts belong to the deformation model: without a mesh they would be silently ignored.
  if (!o.parts_out.empty() && o.mesh_path.empty()) throw std::invalid_argument("--part-file-out needs --mesh (parts are made with the mesh)");
  if (!o.parts_path.empty() && o.mesh_path.empty()) throw std::invalid_argument("--part-file needs --mesh (parts are made with the mesh)");
  const Capture training = read_capture(o.capture_path);
  if (!o.mesh_path.empty() && !in_capture_frame(o, training)) {
    if (!o.landmarks_path.empty() || !o.parts_path.empty() || !o.surface_in.empty() || !deformation.register_mesh)
      throw std::invalid_argument("--landmarks, --part-file, --surface and --no-register are for a mesh in the capture's pose, not "
                                  "the body template or a scan");
    return build_actor(o, training, out);
  }
  std::vector<std::array<int, 3>> triangles;
  if (!o.surface_in.empty()) triangles = read_marker_surface_obj(o.surface_in, static_cast<int>(training.labelled_points().size()));
  SubjectBuildReport report;
  const SubjectModel model = build_subject(training, o.subject, o.surface_in.empty() ? nullptr : &triangles, &report);
  std::optional<DeformationModel> deformation_model;
  DeformationBuildReport deformation_report;
  if (!o.mesh_path.empty()) {
    // A mesh made in the capture's own reference pose (in_capture_frame) is registered as it is.
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
    // The registration may move the skin onto the markers; it may not crumple it.
    const SurfaceCheck check = check_surface(mesh.vertices, deformation_model->reference_vertices, mesh.faces,
                                             SurfaceCheckLimits::at_rest());
    if (!check.ok()) throw std::invalid_argument("refused, nothing written: the registration damaged the mesh: " + check.problem);
    deformation_model->rest_vertices = mesh.vertices;
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
