#pragma once
// Small helpers shared by the subcommands for JSON output.
#include <nlohmann/json.hpp>

#include "core/evaluation/error_stats.h"
#include "core/deform/deformation_model.h"
#include "core/offline/deformation_builder.h"
#include "core/offline/part_joints.h"
#include "core/offline/quadratic_ridge_selection.h"
#include "core/offline/rbf_ridge_selection.h"

namespace skinstream::cli {

inline nlohmann::json to_json(const ErrorStats& s) {
  return {{"count", s.count}, {"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

// Per part the ridge of eq. 6's quadratic modes or of eq. 7 (QuadraticRidgeChoice,
// RidgeChoice) and the leave-one-out miss that chose it (null where the exact fit interpolates
// a member and so cannot predict it).
template <typename Choice>
nlohmann::json to_json(const std::vector<Choice>& parts) {
  nlohmann::json out = nlohmann::json::array();
  for (const Choice& c : parts)
    out.push_back({{"ridge", c.ridge}, {"loo_rms_mm", c.loo_rms_mm}, {"loo_rms_exact_mm", c.loo_rms_exact_mm}});
  return out;
}

// The jointed part pairs the vertex weights split at (part_joints.h).
inline nlohmann::json joints_json(const std::vector<PartJoint>& joints) {
  nlohmann::json out = nlohmann::json::array();
  for (const PartJoint& j : joints)
    out.push_back({{"parts", {j.first, j.second}},
                   {"centre_mm", {j.centre.x(), j.centre.y(), j.centre.z()}},
                   {"residual_mm", j.residual_mm},
                   {"relative_motion_mm", j.relative_motion_mm},
                   {"axis_spread", j.axis_spread}});
  return out;
}

// Per part: its marker-surface triangles, its members (inside and boundary markers) and the
// rigid fit's RMS over the training take. A part of a few triangles and markers with a large
// residual is one a hand adjustment (build-subject --part-file-out) should fold into a neighbour.
inline nlohmann::json part_sizes_json(const DeformationBuildReport& report, const DeformationModel& model) {
  nlohmann::json out = nlohmann::json::array();
  for (int p = 0; p < model.part_count(); ++p)
    out.push_back({{"part", p},
                   {"triangles", report.part_triangles[p]},
                   {"members", model.part_member_offsets[p + 1] - model.part_member_offsets[p]},
                   {"rigid_rms_mm", report.part_rigid_rms_mm[p]}});
  return out;
}

// The parts and vertex weights of a deformation build, in the order build-subject and
// eval-deform both report them. `boundary_rings`: the rule the build was given.
inline void add_parts_and_weights_json(nlohmann::ordered_json& out, const DeformationBuildReport& report,
                                       const DeformationModel& model, int boundary_rings) {
  out["max_part_rigid_rms_mm"] = report.max_part_rigid_rms_mm;
  out["part_sizes"] = part_sizes_json(report, model);
  out["part_file_unused_parts"] = report.unused_parts;
  out["boundary_rings"] = boundary_rings;
  out["boundary_markers"] = report.boundary_markers;
  out["mean_parts_per_vertex"] = report.mean_influences_per_vertex;
  out["fold_smoothed_vertices"] = report.fold_smoothed_vertices;
  out["fold_band_mm"] = report.fold_band_mm;
  out["joints"] = joints_json(report.joints);
  out["joint_blend_mm"] = report.joint_blend_mm;
  out["part_quadratic_ridges"] = to_json(report.part_quadratic_ridges);
  out["part_rbf_ridges"] = to_json(report.part_ridges);
}

}  // namespace skinstream::cli
