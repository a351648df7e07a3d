#include "clients/skinstream/actor_subject.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "core/capture_filler.h"
#include "core/deform/mesh_deformer.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream::cli {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

ActorSubject build_actor_subject(const Capture& training, const FitBody& body, std::span<const MarkerPrior> priors,
                                 const ActorSubjectOptions& options) {
  const std::vector<int> channels = training.labelled_points();
  const int markers = static_cast<int>(channels.size());
  if (markers < 4) throw std::invalid_argument("the take has " + std::to_string(markers) + " labelled markers; a body needs at least 4");
  if (static_cast<int>(priors.size()) != markers)
    throw std::invalid_argument("one marker prior per labelled marker is needed");
  ActorSubject out;
  // One reference frame for the fit and the marker model: every marker present, limbs spread.
  SubjectBuildOptions subject_options = options.subject;
  if (subject_options.reference_frame < 0) {
    subject_options.reference_frame = choose_reference_frame(training, channels);
    if (subject_options.reference_frame < 0)
      throw std::invalid_argument("no frame of the take has all " + std::to_string(markers) +
                                  " labelled markers: the reference pose needs one complete frame");
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<Vec3> frames(static_cast<size_t>(training.frame_count) * markers);
  for (int f = 0; f < training.frame_count; ++f)
    for (int i = 0; i < markers; ++i) frames[static_cast<size_t>(f) * markers + i] = training.at(f, channels[i]);
  out.motion = measure_take_motion(frames, training.frame_count, markers, options.motion);
  if (!out.motion.ok()) throw std::invalid_argument("refused, nothing written: " + out.motion.problem);
  const std::vector<Triangle>& triangles = body.triangles;
  out.fit = fit_actor(body, frames, training.frame_count, markers, subject_options.reference_frame, priors, options.fit);
  out.fit_seconds = seconds_since(start);

  const auto build_start = std::chrono::steady_clock::now();
  out.model = build_subject(training, subject_options, nullptr, &out.subject_report);
  // Parts and weights need every marker every frame: the take filled by this model.
  const Capture filled = fill_capture(out.model, training, CaptureFillOptions{});
  std::vector<Vec3> positions(static_cast<size_t>(filled.frame_count) * markers);
  for (int f = 0; f < filled.frame_count; ++f)
    for (int i = 0; i < markers; ++i) positions[static_cast<size_t>(f) * markers + i] = filled.at(f, i);
  out.skeleton_parts = options.parts == PartChoiceRule::Skeleton ||
                       (options.parts == PartChoiceRule::Automatic && markers < options.skeleton_parts_below);
  // The registered fitted template (both paths start from it). Where the fit left the markers
  // far from the skin (a short take with little range of motion), pulling the skin onto them
  // folds it: then the fitted template is used as it is, and the report says why.
  out.deformation = build_skeletal_deformation_model(out.model, out.fit, triangles, positions, filled.frame_count,
                                                     options.skeletal, &out.skeletal_report);
  const SurfaceCheck registration =
      check_surface(out.fit.reference_vertices, out.deformation.reference_vertices, triangles, options.limits.registration);
  if (!registration.ok()) {
    out.registration_skipped = "the registration would damage the body (" + registration.problem + ")";
    SkeletalDeformationOptions unregistered = options.skeletal;
    unregistered.register_mesh = false;
    out.deformation = build_skeletal_deformation_model(out.model, out.fit, triangles, positions, filled.frame_count,
                                                       unregistered, &out.skeletal_report);
  }
  if (!out.skeleton_parts) {
    DeformationBuildOptions dense = options.marker_parts;
    dense.register_mesh = false;
    const std::vector<Vec3> registered = out.deformation.reference_vertices;
    out.deformation = build_deformation_model(out.model, positions, filled.frame_count, registered, triangles, dense,
                                              &out.marker_parts_report);
    out.deformation.rest_vertices = out.fit.rest_vertices;
    out.deformation.registration_rms_mm = out.skeletal_report.registration.after.rms;
  }
  out.build_seconds = seconds_since(build_start);

  // The checks, on the subject as built and on its training take deformed by it.
  const auto check_start = std::chrono::steady_clock::now();
  MeshDeformer deformer(out.deformation, out.model);
  std::vector<std::vector<Vec3>> deformed;
  std::vector<int> deformed_frames;
  std::vector<float> buffer(3 * static_cast<size_t>(out.deformation.vertex_count()));
  const int checks = std::max(1, std::min(options.check_frames, filled.frame_count));
  for (int k = 0; k < checks; ++k) {
    const int f = static_cast<int>((static_cast<long long>(k) * filled.frame_count) / checks);
    if (!deformer.deform(std::span<const Vec3>(positions).subspan(static_cast<size_t>(f) * markers, static_cast<size_t>(markers)),
                         buffer, {}))
      continue;
    std::vector<Vec3> mesh(static_cast<size_t>(out.deformation.vertex_count()));
    for (size_t v = 0; v < mesh.size(); ++v) mesh[v] = Vec3(buffer[3 * v], buffer[3 * v + 1], buffer[3 * v + 2]);
    deformed.push_back(std::move(mesh));
    deformed_frames.push_back(f);
  }
  out.check = check_subject(out.fit, body, out.deformation, out.model.marker_names, deformed, deformed_frames, options.limits);
  out.check_seconds = seconds_since(check_start);
  return out;
}

}  // namespace skinstream::cli
