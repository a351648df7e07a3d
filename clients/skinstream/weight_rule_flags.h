#pragma once
// The switches of the weight rules this build adds to the paper's (section 5.2), shared by
// build-subject and eval-deform (command_line.cpp spells them once for both). Each flag
// gives back an earlier rule; all of them together (--boundary-rings 0 --no-joint-split
// --no-fold-blend) give the paper's rule alone.
#include "core/offline/deformation_builder.h"

namespace skinstream::cli {

struct WeightRuleFlags {
  bool no_joint_split = false;     // no split of the vertex weights at hinge joints
  bool no_joint_blend = false;     // the split a hard switch at the plane, not a ramp
  bool no_fold_blend = false;      // no blend of the vertex weights across folds
  bool no_fold_smoothing = false;  // the fold blend's weights not smoothed over the mesh
  int boundary_rings = MarkerWeightOptions{}.boundary_rings;  // marker weights' boundary widened
};

// Sets the rules of `build` the flags name.
void apply_weight_rules(const WeightRuleFlags& flags, DeformationBuildOptions& build);

}  // namespace skinstream::cli
