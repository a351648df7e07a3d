#pragma once
// A subject for a real actor from a training take and a body template: the template fitted to
// the actor's markers (core/fitting/actor_fit.h), the section 4 marker model in the same
// reference frame, the detailed mesh registered and made deformable (by the fitted skeleton's
// segments for a sparse marker set, by the paper's mean-shift parts for a dense one), and the
// checks of what came out. Shared by build-subject and eval-actor.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/body/body.h"
#include "core/fitting/actor_fit.h"
#include "core/fitting/skeletal_deformation_builder.h"
#include "core/fitting/subject_checks.h"
#include "core/fitting/take_motion.h"
#include "core/offline/deformation_builder.h"
#include "core/offline/subject_builder.h"

namespace skinstream::cli {

enum class PartChoiceRule { Automatic, Skeleton, Markers };

struct ActorSubjectOptions {
  SubjectBuildOptions subject;
  TakeMotionLimits motion;  // a take that does not move like a body is refused before the fit
  ActorFitOptions fit;
  SkeletalDeformationOptions skeletal;
  DeformationBuildOptions marker_parts;  // the dense path (its mesh is registered already)
  PartChoiceRule parts = PartChoiceRule::Automatic;
  int skeleton_parts_below = 120;  // Automatic: the skeleton's segments for fewer markers than this
  SubjectCheckLimits limits;
  int check_frames = 30;           // training frames deformed for the checks, spread over the take
};

struct ActorSubject {
  SubjectModel model;
  DeformationModel deformation;
  TakeMotion motion;
  ActorFit fit;
  SubjectBuildReport subject_report;
  bool skeleton_parts = false;
  SkeletalDeformationReport skeletal_report;  // the registration, and the parts when skeleton_parts
  std::string registration_skipped;           // why the fitted template was used unregistered, if it was
  DeformationBuildReport marker_parts_report; // otherwise
  SubjectCheck check;      // check.problem empty: plausible
  double fit_seconds = 0.0, build_seconds = 0.0, check_seconds = 0.0;
};

// training: the take (labelled channels are the markers); body: the body to fit (the template
// with its bones, fit_body_of(), or a scan made a skinned body, scan_body.h); priors: one per
// labelled marker (core/fitting/marker_priors.h). Throws std::invalid_argument with one line
// when the take cannot make a subject (no complete frame, too few markers, a take that does not
// articulate); a subject whose checks fail is returned with check.problem set (the caller
// refuses it).
ActorSubject build_actor_subject(const Capture& training, const FitBody& body, std::span<const MarkerPrior> priors,
                                 const ActorSubjectOptions& options = {});

}  // namespace skinstream::cli
