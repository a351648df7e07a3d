#include "core/fitting/skeletal_deformation_builder.h"

#include <cmath>
#include <stdexcept>

#include "core/deform/part_model.h"
#include "core/deform/skeleton_solver.h"

namespace skinstream {

DeformationModel build_skeletal_deformation_model(const SubjectModel& subject, const ActorFit& fit,
                                                  std::span<const Triangle> triangles, std::span<const Vec3> training,
                                                  int frame_count, const SkeletalDeformationOptions& options,
                                                  SkeletalDeformationReport* out_report) {
  const int markers = subject.marker_count();
  if (static_cast<int>(fit.attachments.size()) != markers)
    throw std::invalid_argument("the fit has " + std::to_string(fit.attachments.size()) + " markers, the subject " +
                                std::to_string(markers));
  if (frame_count <= 0 || training.size() != static_cast<size_t>(frame_count) * markers)
    throw std::invalid_argument("the training take is not frame_count x markers");
  if (fit.reference_vertices.size() != fit.rest_vertices.size() || fit.reference_vertices.empty())
    throw std::invalid_argument("the fit has no posed template");
  SkeletalDeformationReport report;
  DeformationModel model;
  model.faces.assign(triangles.begin(), triangles.end());
  model.rest_vertices = fit.rest_vertices;

  // 5.1: each marker's skin point (its centre minus its fitted height along the surface's
  // normal) is the landmark of its fitted place; the data term holds the rest of the surface.
  std::vector<Vec3> skin_targets(static_cast<size_t>(markers));
  std::vector<RegistrationLandmark> landmarks;
  for (int i = 0; i < markers; ++i) {
    const MarkerAttachment& a = fit.attachments[i];
    const Triangle& t = triangles[static_cast<size_t>(a.triangle)];
    const Vec3 n = triangle_normal(fit.reference_vertices[t[0]], fit.reference_vertices[t[1]], fit.reference_vertices[t[2]]);
    skin_targets[i] = subject.reference_positions[i] - a.offset_mm * n;
    landmarks.push_back({i, t[0], a.triangle, a.barycentric});
  }
  if (options.register_mesh) {
    RegistrationOptions registration = options.registration;
    registration.marker_offset_mm = 0.0;  // the targets are on the skin already
    model.reference_vertices =
        register_mesh(fit.reference_vertices, triangles, skin_targets, landmarks, registration, &report.registration);
    report.registered = true;
  } else {
    model.reference_vertices = fit.reference_vertices;
    report.registration.before = report.registration.after = marker_surface_distance(model.reference_vertices, triangles, skin_targets);
  }
  model.registration_rms_mm = report.registration.after.rms;

  // Parts: the segments. Members: markers with at least member_weight of their motion on it.
  model.skeleton = fit.reference_skeleton;
  const int parts = model.skeleton.segment_count();
  model.skeleton.part_segment.resize(static_cast<size_t>(parts));
  for (int p = 0; p < parts; ++p) {
    model.skeleton.part_segment[p] = p;
    model.part_names.push_back(model.skeleton.segments[p].name);
    for (int i = 0; i < markers; ++i)
      for (int k = model.skeleton.marker_weight_offsets[i]; k < model.skeleton.marker_weight_offsets[i + 1]; ++k) {
        const SegmentWeight& w = model.skeleton.marker_weights[k];
        if (w.segment == p && w.weight >= options.member_weight) model.part_members.push_back({i, std::min(1.0, w.weight)});
      }
    // A segment no marker sits on (the neck of most sets) still moves with the skeleton; the
    // subscriber protocol gives every part a member, so it lends the marker nearest its pivot,
    // which with one member feeds neither eq. 6 nor eq. 7.
    if (static_cast<int>(model.part_members.size()) == model.part_member_offsets.back()) {
      int nearest = 0;
      for (int i = 1; i < markers; ++i)
        if ((subject.reference_positions[i] - model.skeleton.segments[p].pivot).norm() <
            (subject.reference_positions[nearest] - model.skeleton.segments[p].pivot).norm())
          nearest = i;
      model.part_members.push_back({nearest, 1e-3});
    }
    model.part_member_offsets.push_back(static_cast<int>(model.part_members.size()));
  }
  // Vertex weights: the template's skin weights per segment.
  for (int v = 0; v < fit.vertex_weights.vertex_count(); ++v) {
    for (int k = fit.vertex_weights.offsets[v]; k < fit.vertex_weights.offsets[v + 1]; ++k)
      model.vertex_influences.push_back({fit.vertex_weights.weights[k].segment, fit.vertex_weights.weights[k].weight});
    model.vertex_influence_offsets.push_back(static_cast<int>(model.vertex_influences.size()));
  }

  // The skeleton's pose over the training take: the parts' rigid motions the ridges are chosen with.
  SkeletonSolver solver(model.skeleton, subject.reference_positions);
  std::vector<std::vector<RigidTransform>> motions(static_cast<size_t>(parts), std::vector<RigidTransform>(static_cast<size_t>(frame_count)));
  double squared = 0.0;
  for (int f = 0; f < frame_count; ++f) {
    solver.solve(training.subspan(static_cast<size_t>(f) * markers, static_cast<size_t>(markers)));
    squared += solver.rms_mm() * solver.rms_mm();
    for (int p = 0; p < parts; ++p) motions[p][f] = solver.segment_motion(p);
  }
  report.skeleton_rms_mm = std::sqrt(squared / frame_count);

  for (int p = 0; p < parts; ++p) {
    PartChoice choice;
    choice.name = model.part_names[p];
    std::vector<int> members;
    std::vector<Vec3> reference;
    for (int k = model.part_member_offsets[p]; k < model.part_member_offsets[p + 1]; ++k) {
      members.push_back(model.part_members[k].marker);
      reference.push_back(subject.reference_positions[members.back()]);
    }
    choice.members = static_cast<int>(members.size());
    choice.quadratic = choice.members >= options.quadratic_members;
    choice.rbf = choice.members >= 2;
    if (choice.quadratic) {
      const QuadraticRidgeChoice q = choose_quadratic_ridge(reference, members, training, frame_count, markers,
                                                            options.sample_frames, motions[p]);
      choice.quadratic_ridge = q.ridge;
    }
    if (choice.rbf) {
      PartModel part = build_part_model(reference, choice.quadratic_ridge);
      part.quadratic = choice.quadratic;
      choice.rbf = part.rbf_dilation > 0.0;
      if (choice.rbf)
        choice.rbf_ridge = choose_rbf_ridge(part, members, training, frame_count, markers, options.sample_frames, motions[p]).ridge;
    }
    const std::string count = std::to_string(choice.members) + (choice.members == 1 ? " member" : " members");
    const bool lent = choice.members == 1 && model.part_members[model.part_member_offsets[p]].weight < options.member_weight;
    if (lent) {
      choice.members = 0;
      choice.why = "no marker of its own: the segment's motion alone";
    } else if (choice.quadratic) choice.why = count + ": quadratic + RBF";
    else if (choice.rbf) choice.why = count + ": rigid + RBF (eq. 6 needs " + std::to_string(options.quadratic_members) + ")";
    else choice.why = count + ": the segment's motion alone (eq. 7 needs 2)";
    model.part_quadratic.push_back(choice.quadratic ? 1 : 0);
    model.part_quadratic_ridge.push_back(choice.quadratic_ridge);
    model.part_rbf_ridge.push_back(choice.rbf_ridge);
    report.parts.push_back(choice);
  }

  const std::string problem = model.validate(markers);
  if (!problem.empty()) throw std::invalid_argument("built an inconsistent " + problem);
  if (out_report) *out_report = report;
  return model;
}

}  // namespace skinstream
