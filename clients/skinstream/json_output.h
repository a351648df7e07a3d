#pragma once
// Small helpers shared by the subcommands for JSON output.
#include <nlohmann/json.hpp>

#include "core/evaluation/error_stats.h"
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

}  // namespace skinstream::cli
