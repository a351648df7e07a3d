#include "clients/skinstream/weight_rule_flags.h"

namespace skinstream::cli {

void apply_weight_rules(const WeightRuleFlags& flags, DeformationBuildOptions& build) {
  build.split_at_joints = !flags.no_joint_split;
  build.blend_at_joints = !flags.no_joint_blend;
  build.blend_folds = !flags.no_fold_blend;
  build.smooth_folds = !flags.no_fold_smoothing;
  build.weights.boundary_rings = flags.boundary_rings;
}

}  // namespace skinstream::cli
