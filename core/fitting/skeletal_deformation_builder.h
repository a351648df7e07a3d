#pragma once
// Section 5 on a fitted template (actor_fit.h): the detailed mesh is the template as fitted to
// the actor in the reference frame, registered to the markers for the last millimetres (5.1,
// Allen et al. 2003, with each marker's fitted place as its landmark); the parts are the
// template's segments, each moved by its segment's motion in the skeleton's pose fitted to the
// markers per frame; a vertex's part weights are the template's own skin weights summed per
// segment (so that with no other term the body moves by linear blend skinning); a marker
// belongs to a part when its weight on the segment reaches the paper's 0.2.
//
// The terms each part can carry are chosen from its members: eq. 6 (quadratic) needs many
// markers in the part to be more than a wobble through a few of them, eq. 7 (RBF) needs two;
// a part with fewer moves rigidly with its segment. The report says what was picked and why.

#include <span>
#include <string>
#include <vector>

#include "core/deform/deformation_model.h"
#include "core/fitting/actor_fit.h"
#include "core/offline/mesh_registration.h"
#include "core/offline/quadratic_ridge_selection.h"
#include "core/offline/rbf_ridge_selection.h"
#include "core/subject_model.h"

namespace skinstream {

struct SkeletalDeformationOptions {
  bool register_mesh = true;          // false: the fitted template as it is
  RegistrationOptions registration;   // its offset is taken per marker from the fit
  double member_weight = 0.2;         // the paper's threshold for a marker to join a part
  int quadratic_members = 12;         // eq. 6 for parts with at least this many members
  int sample_frames = 48;             // training frames the ridges are chosen over
};

struct PartChoice {
  std::string name;
  int members = 0;
  bool quadratic = false;
  bool rbf = false;
  std::string why;  // e.g. "3 members: rigid + RBF (eq. 6 needs 12)"
  double quadratic_ridge = 0.0;
  double rbf_ridge = 0.0;
};

struct SkeletalDeformationReport {
  bool registered = false;
  RegistrationReport registration;
  std::vector<PartChoice> parts;
  double skeleton_rms_mm = 0.0;  // the per-frame pose fit's miss over the training take, RMS
};

// subject: the marker model (its reference pose is the fit's reference frame); fit: the fitted
// template; triangles: the template's; training: frame_count x markers, frame-major, all present
// (the take filled). Throws std::invalid_argument on unusable input.
DeformationModel build_skeletal_deformation_model(const SubjectModel& subject, const ActorFit& fit,
                                                  std::span<const Triangle> triangles, std::span<const Vec3> training,
                                                  int frame_count, const SkeletalDeformationOptions& options = {},
                                                  SkeletalDeformationReport* out_report = nullptr);

}  // namespace skinstream
