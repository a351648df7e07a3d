#include "clients/skinstream/weight_rule_flags.h"

#include <CLI/CLI.hpp>

namespace skinstream::cli {

void add_weight_rule_flags(CLI::App& command, WeightRuleFlags& flags) {
  command.add_flag("--no-joint-split", flags.no_joint_split, "no split of the vertex weights at hinge joints");
  command.add_flag("--no-joint-blend", flags.no_joint_blend,
                   "split at hinge joints with a hard switch at the plane, not a ramp half a marker spacing either side");
  command.add_flag("--no-fold-blend", flags.no_fold_blend,
                   "no blend of the vertex weights across folds (with --no-joint-split: the paper's nearest triangle alone)");
  command.add_flag("--no-fold-smoothing", flags.no_fold_smoothing,
                   "keep the fold blend's vertex weights as they are, not smoothed over the mesh inside folds");
  command
      .add_option("--boundary-rings", flags.boundary_rings,
                  "widen the marker weights' part boundaries by this many rings of the marker surface (0: the paper's)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
}

void apply_weight_rules(const WeightRuleFlags& flags, DeformationBuildOptions& build) {
  build.split_at_joints = !flags.no_joint_split;
  build.blend_at_joints = !flags.no_joint_blend;
  build.blend_folds = !flags.no_fold_blend;
  build.smooth_folds = !flags.no_fold_smoothing;
  build.weights.boundary_rings = flags.boundary_rings;
}

}  // namespace skinstream::cli
