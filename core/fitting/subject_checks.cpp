#include "core/fitting/subject_checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace skinstream {

namespace {

// Segment lengths as fractions of the height (Drillis & Contini 1966, as Winter tabulates them):
// joint centre to joint centre. Shoulder and hip widths are between the joint centres, narrower
// than the bony widths those tables give (biacromial 0.259, bi-iliac 0.191; the hip joint
// centres lie about a third of the pelvis's width inside its outline).
struct HumanFraction {
  const char* name;
  const char* from;
  const char* to;
  double fraction;
};
constexpr HumanFraction kFractions[] = {
    {"upper arm left", "upperarm.L", "forearm.L", 0.186}, {"upper arm right", "upperarm.R", "forearm.R", 0.186},
    {"forearm left", "forearm.L", "hand.L", 0.146},       {"forearm right", "forearm.R", "hand.R", 0.146},
    {"thigh left", "thigh.L", "shank.L", 0.245},          {"thigh right", "thigh.R", "shank.R", 0.245},
    {"shank left", "shank.L", "foot.L", 0.246},           {"shank right", "shank.R", "foot.R", 0.246},
    {"shoulder width", "upperarm.L", "upperarm.R", 0.20}, {"hip width", "thigh.L", "thigh.R", 0.11},
};

std::string fixed(double v, int digits = 1) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

}  // namespace

SubjectCheck check_subject(const ActorFit& fit, const FitBody& body, const DeformationModel& model,
                           std::span<const std::string> marker_names,
                           std::span<const std::vector<Vec3>> deformed_take, std::span<const int> take_frames,
                           const SubjectCheckLimits& limits) {
  if (model.rest_vertices.size() != model.reference_vertices.size() || fit.reference_vertices.size() != model.reference_vertices.size())
    throw std::invalid_argument("check_subject: the model and the fit do not share the template's vertices");
  if (marker_names.size() != fit.marker_rms_mm.size())
    throw std::invalid_argument("check_subject: one name per fitted marker is needed");
  if (deformed_take.size() != take_frames.size()) throw std::invalid_argument("check_subject: one index per deformed frame");
  SubjectCheck out;
  out.take_edge_stretch_limit = limits.take.max_edge_stretch;
  out.registration = check_surface(fit.reference_vertices, model.reference_vertices, model.faces, limits.registration);
  out.pose = check_surface(model.rest_vertices, model.reference_vertices, model.faces, limits.pose);
  for (size_t k = 0; k < deformed_take.size(); ++k) {
    const SurfaceCheck c = check_surface(model.rest_vertices, deformed_take[k], model.faces, limits.take);
    ++out.take_frames_checked;
    if (c.longest_stretched_edge > out.take_longest_stretched_edge) {
      out.take_longest_stretched_edge = c.longest_stretched_edge;
      out.take_longest_stretched_edge_frame = take_frames[k];
    }
    const bool worse = out.worst_take_frame_index < 0 || !c.ok() > !out.worst_take_frame.ok() ||
                       (c.ok() == out.worst_take_frame.ok() && c.strained_fraction > out.worst_take_frame.strained_fraction);
    if (worse) {
      out.worst_take_frame = c;
      out.worst_take_frame_index = take_frames[k];
    }
  }

  std::vector<std::pair<double, std::string>> unplaced;
  int seen = 0;
  for (size_t i = 0; i < fit.marker_rms_mm.size(); ++i) {
    const double miss = fit.marker_rms_mm[i];
    if (!std::isfinite(miss)) continue;
    ++seen;
    if (miss > limits.unplaced_mm) unplaced.push_back({miss, marker_names[i] + " (" + fixed(miss, 0) + " mm)"});
  }
  std::sort(unplaced.begin(), unplaced.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& u : unplaced) out.unplaced_markers.push_back(u.second);

  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const Vec3& v : fit.rest_vertices) {
    low = std::min(low, v.z());
    high = std::max(high, v.z());
  }
  out.height_mm = high - low;
  for (const HumanFraction& f : kFractions) {
    const int a = body.find(f.from), b = body.find(f.to);
    if (a < 0 || b < 0) continue;
    const double expected = f.fraction * out.height_mm;
    out.lengths.push_back({f.name, (fit.rest_pivots[a] - fit.rest_pivots[b]).norm(), expected * (1.0 - limits.length_tolerance),
                           expected * (1.0 + limits.length_tolerance)});
  }

  // The first problem, in the order a user can act on: the markers, the body's size, then what
  // the fit and the registration made of them.
  if (seen == 0) {
    out.problem = "no marker was seen in the fit frames";
  } else if (static_cast<double>(unplaced.size()) > limits.max_unplaced_fraction * seen) {
    out.problem = "the markers cannot be placed on a body: " + std::to_string(unplaced.size()) + " of " +
                  std::to_string(seen) + " miss the fitted body by more than " + fixed(limits.unplaced_mm, 0) +
                  " mm (worst " + out.unplaced_markers.front() + ")";
  } else if (out.height_mm < limits.min_height_mm || out.height_mm > limits.max_height_mm) {
    out.problem = "the fitted body is " + fixed(out.height_mm, 0) + " mm tall, outside " + fixed(limits.min_height_mm, 0) +
                  "-" + fixed(limits.max_height_mm, 0) + " mm";
  }
  if (out.problem.empty())
    for (const SegmentLength& l : out.lengths)
      if (l.mm < l.low_mm || l.mm > l.high_mm) {
        out.problem = "the fitted " + l.name + " is " + fixed(l.mm, 0) + " mm, outside the human range " + fixed(l.low_mm, 0) +
                      "-" + fixed(l.high_mm, 0) + " mm for a body " + fixed(out.height_mm, 0) + " mm tall";
        break;
      }
  if (out.problem.empty() && !out.registration.ok()) out.problem = "the registration damaged the body: " + out.registration.problem;
  if (out.problem.empty() && !out.pose.ok()) out.problem = "the body in the reference pose is crumpled: " + out.pose.problem;
  if (out.problem.empty() && out.worst_take_frame_index >= 0 && !out.worst_take_frame.ok())
    out.problem = "the training take crumples the body at frame " + std::to_string(out.worst_take_frame_index) + ": " +
                  out.worst_take_frame.problem;
  return out;
}

}  // namespace skinstream
