#pragma once
// Is a subject built for an actor plausible, before anything uses it? A crumpled or sprayed
// body, markers the fit could not put on the body, limbs no human has: each is measured, the
// figures reported, and the first that is out of bounds named in one line.
//   registration  the registered mesh against the fitted template in the same pose: the
//                 registration may move the skin, not fold, cross or tear it;
//   pose          the reference pose against the template's rest pose (linear blend skinning's
//                 creases allowed: surface_checks.h's defaults);
//   take          the training take deformed by the subject, frame by frame, the same way;
//   markers       each marker's miss over the fit frames: a marker the fit cannot place (a
//                 mislabelled one, a prop) is named; too many of them is not a body;
//   proportions   the fitted segment lengths against human ranges (Drillis & Contini's
//                 fractions of the height, 40% either way) and the height itself.

#include <span>
#include <string>
#include <vector>

#include "core/deform/deformation_model.h"
#include "core/fitting/actor_fit.h"
#include "core/fitting/surface_checks.h"

namespace skinstream {

struct SubjectCheckLimits {
  // The registration moves the skin onto the markers' skin points (10-30 mm where the fit left
  // them): no strain beyond the at-rest limits, and at most a handful of triangles turned or
  // pressed through where the template nearly touches itself (measured on real takes: 0-1
  // turned, 20-45 crossing at the toes, the armpits and the crotch, of 26,756).
  SurfaceCheckLimits registration = registration_limits();
  // A real reference pose bends more than a test pose: the trunk bent 40 degrees back turns 27
  // triangles in its creases (measured, CMU 85_02), a crumpled body thousands.
  SurfaceCheckLimits pose = posed_limits();
  // A take is implausible when some frame crumples far past the target: the target (1% of edges
  // beyond 1.5) is reported, this is what refuses.
  SurfaceCheckLimits take = take_limits();
  double unplaced_mm = 40.0;          // a marker missing the fit by more (RMS) is not placed
  double max_unplaced_fraction = 0.25;
  double min_height_mm = 900.0, max_height_mm = 2300.0;
  double length_tolerance = 0.4;  // segment length within (1 +- this) of the human fraction

  static SurfaceCheckLimits registration_limits() {
    SurfaceCheckLimits limits = SurfaceCheckLimits::at_rest();
    limits.max_flipped_fraction = 2e-4;
    limits.max_self_intersecting_fraction = 2e-3;
    return limits;
  }
  static SurfaceCheckLimits posed_limits() {
    SurfaceCheckLimits limits;
    // Refused is what is crumpled, not what misses the 1% target (reported beside it): linear
    // blend skinning alone strains 0.4-1.5% of the edges in real reference poses.
    limits.max_strained_fraction = 0.05;
    limits.max_flipped_fraction = 0.003;
    // A scan in a T pose brought down to an A-like reference pose stretches its armpits' edges
    // to 13 typical edges; a shard pulled half a metre off the template, over 30.
    limits.max_edge_stretch = 25.0;
    return limits;
  }
  static SurfaceCheckLimits take_limits() {
    SurfaceCheckLimits limits;
    limits.max_strained_fraction = 0.10;
    limits.max_flipped_fraction = 0.01;
    limits.max_self_intersecting_fraction = 0.05;
    return limits;
  }
};

struct SegmentLength {
  std::string name;  // e.g. "upper arm left"
  double mm = 0.0;
  double low_mm = 0.0, high_mm = 0.0;
};

struct SubjectCheck {
  SurfaceCheck registration;
  SurfaceCheck pose;
  SurfaceCheck worst_take_frame;  // the frame with the most strained edges
  int worst_take_frame_index = -1;
  // The take's longest stretched edge over the frames checked, in typical edges, and its frame:
  // how near the take came to the stretch limit, which any one frame can cross.
  double take_longest_stretched_edge = 0.0;
  int take_longest_stretched_edge_frame = -1;
  double take_edge_stretch_limit = 0.0;  // the limit it was checked against
  int take_frames_checked = 0;
  std::vector<std::string> unplaced_markers;  // by name, worst first
  double height_mm = 0.0;
  std::vector<SegmentLength> lengths;
  std::string problem;  // empty: plausible; else the first failing check, one line

  bool ok() const { return problem.empty(); }
};

// fit: the actor fit the subject was built from; model: its deformation model (reference pose,
// rest vertices, faces); marker_names: the subject's, for the report; deformed_take: meshes of
// the training take deformed by the model (any number, each model.vertex_count() positions), the
// caller's choice of frames (take_frames: their indices, for the report).
SubjectCheck check_subject(const ActorFit& fit, const FitBody& body, const DeformationModel& model,
                           std::span<const std::string> marker_names,
                           std::span<const std::vector<Vec3>> deformed_take, std::span<const int> take_frames,
                           const SubjectCheckLimits& limits = {});

}  // namespace skinstream
