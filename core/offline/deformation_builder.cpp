#include "core/offline/deformation_builder.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/offline/marker_distance_stats.h"
#include "core/offline/vertex_part_weights.h"

namespace skinstream {

DeformationModel build_deformation_model(const SubjectModel& subject, std::span<const Vec3> training, int frame_count,
                                         std::span<const Vec3> mesh_vertices,
                                         std::span<const std::array<int, 3>> mesh_faces,
                                         const DeformationBuildOptions& options, DeformationBuildReport* out_report) {
  DeformationBuildReport report;
  if (mesh_vertices.empty() || mesh_faces.empty()) throw std::invalid_argument("the detailed mesh has no vertices or no faces");
  if (subject.triangles.empty()) throw std::invalid_argument("the subject has no marker surface");
  const std::span<const Vec3> markers(subject.reference_positions);

  DeformationModel model;
  model.faces.assign(mesh_faces.begin(), mesh_faces.end());

  // 5.1: registration to the reference marker surface.
  if (options.register_mesh) {
    std::vector<RegistrationLandmark> landmarks = options.landmarks;
    if (landmarks.empty()) landmarks = guess_landmarks(mesh_vertices, markers, options.landmark_guess);
    report.landmarks = static_cast<int>(landmarks.size());
    model.reference_vertices =
        register_mesh(mesh_vertices, mesh_faces, markers, landmarks, options.registration, &report.registration);
    report.registered = true;
    model.registration_rms_mm = report.registration.after.rms;
  } else {
    model.reference_vertices.assign(mesh_vertices.begin(), mesh_vertices.end());
    report.registration.before = report.registration.after =
        marker_surface_distance(mesh_vertices, mesh_faces, markers, options.registration.marker_offset_mm);
    model.registration_rms_mm = report.registration.after.rms;
  }

  // 5.2: near-rigid parts of the marker surface over the training take.
  const PartSegmentation parts =
      options.part_assignment.empty()
          ? segment_parts(markers, subject.triangles, training, frame_count, options.segmentation)
          : segmentation_from_assignment(markers, subject.triangles, training, frame_count, options.part_assignment,
                                         options.assignment_kind, options.segmentation.sample_frames);
  report.parts = parts.part_count;
  report.mean_shift_groups = parts.mean_shift_groups;
  for (double rms : parts.part_rigid_rms_mm) report.max_part_rigid_rms_mm = std::max(report.max_part_rigid_rms_mm, rms);
  report.part_rigid_rms_mm = parts.part_rigid_rms_mm;
  report.unused_parts = parts.unused_parts;
  report.part_triangles.assign(parts.part_count, 0);
  for (int p : parts.triangle_part) ++report.part_triangles[p];
  report.marker_part = marker_parts(subject.triangles, parts.triangle_part, subject.marker_count());

  const MarkerPartWeights alpha = marker_part_weights(markers, subject.triangles, parts.triangle_part, parts.part_count,
                                                      training, frame_count, options.weights);
  report.boundary_markers = alpha.boundary_markers;
  report.markers_added_for_min_members = alpha.markers_added_for_min_members;
  model.part_member_offsets = alpha.part_member_offsets;
  model.part_members = alpha.part_members;
  for (int p = 0; p < parts.part_count; ++p) model.part_names.push_back("part_" + std::to_string(p));

  std::vector<char> under_marker;
  if (options.split_at_joints) {
    report.joints = fit_part_joints(markers, model.part_member_offsets, model.part_members, training, frame_count,
                                    options.joints);
    if (options.blend_at_joints) report.joint_blend_mm = 0.5 * median_nearest_marker_distance(markers);
  }
  if (options.split_at_joints || options.blend_folds)
    under_marker = vertices_under_markers(model.reference_vertices, mesh_faces, markers);
  VertexPartWeights beta = vertex_part_weights(model.reference_vertices, markers, subject.triangles,
                                               model.part_member_offsets, model.part_members, report.joints, under_marker,
                                               options.blend_folds, report.joint_blend_mm);
  if (options.blend_folds && options.smooth_folds) {
    FoldSmoothingOptions smoothing = options.fold_smoothing;
    if (smoothing.band_mm < 0.0) smoothing.band_mm = 0.5 * median_nearest_marker_distance(markers);
    report.fold_band_mm = smoothing.band_mm;
    report.fold_smoothed_vertices =
        smooth_fold_weights(model.reference_vertices, mesh_faces, under_marker, model.part_count(), beta, smoothing);
  }
  model.vertex_influence_offsets = std::move(beta.vertex_influence_offsets);
  model.vertex_influences = std::move(beta.vertex_influences);
  report.mean_influences_per_vertex =
      static_cast<double>(model.vertex_influences.size()) / static_cast<double>(model.vertex_count());

  // Eq. 6's and then eq. 7's ridge per part, from the members' leave-one-out misses over the
  // training take (eq. 7 fits what eq. 6 leaves, so its ridge is chosen on that fit).
  for (int p = 0; p < model.part_count(); ++p) {
    std::vector<Vec3> reference;
    std::vector<int> members;
    for (int k = model.part_member_offsets[p]; k < model.part_member_offsets[p + 1]; ++k) {
      members.push_back(model.part_members[k].marker);
      reference.push_back(subject.reference_positions[members.back()]);
    }
    const QuadraticRidgeChoice quadratic =
        choose_quadratic_ridge(reference, members, training, frame_count, subject.marker_count());
    model.part_quadratic_ridge.push_back(quadratic.ridge);
    report.part_quadratic_ridges.push_back(quadratic);
    const RidgeChoice choice = choose_rbf_ridge(build_part_model(reference, quadratic.ridge), members, training,
                                                frame_count, subject.marker_count());
    model.part_rbf_ridge.push_back(choice.ridge);
    report.part_ridges.push_back(choice);
  }

  const std::string problem = model.validate(subject.marker_count());
  if (!problem.empty()) throw std::invalid_argument("built an inconsistent " + problem);
  if (out_report) *out_report = report;
  return model;
}

}  // namespace skinstream
