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

}  // namespace skinstream::cli
