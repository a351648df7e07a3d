#pragma once
// skinstream build-subject: training capture -> subject model file (section 4.1-4.3), and with
// a mesh the detailed mesh registered, segmented and weighted for deformation (section 5.1-5.2).
// The mesh is either the body template (a MakeHuman body with its skeleton and weights beside
// it, e.g. replay_data/makehuman/makehuman_hm08_body_only.obj): it is fitted to the actor's
// markers first (core/fitting); or a mesh already in the capture's pose and axes (the same
// subject in the reference frame, e.g. the synthetic demo's): it is registered as it is. Either
// way the subject is checked before it is written, and refused in one line when implausible.
#include <cstdio>
#include <string>

#include "clients/skinstream/actor_subject.h"
#include "clients/skinstream/weight_rule_flags.h"
#include "core/fitting/mesh_frame.h"
#include "core/offline/deformation_builder.h"
#include "core/offline/subject_builder.h"

namespace skinstream::cli {

struct BuildSubjectOptions {
  std::string capture_path;  // training capture, ideally a range-of-motion take
  std::string out_path;      // subject file to write
  std::string surface_in;    // marker surface OBJ to use instead of building one
  std::string surface_out;   // also write the marker surface as OBJ
  std::string mesh_path;     // detailed mesh: adds the deformation model
  std::string marker_sets_dir;  // known marker sets (empty: the bundled ones)
  MeshFrameOptions mesh_frame;  // the mesh's unit and axes, when not detected
  std::string landmarks_path;  // {"marker": vertex index} for registration
  std::string parts_path;      // {"marker": part index} instead of mean shift
  std::string parts_out;       // also write the segmentation used
  SubjectBuildOptions subject;
  DeformationBuildOptions deformation;  // landmarks and parts come from the files above
  WeightRuleFlags weight_rules;
  ActorSubjectOptions actor;            // the template path
};

// Writes the subject (and the files asked for) and prints the build report as JSON to `out`;
// returns the exit code. Throws on bad files or options that contradict each other.
int run_build_subject(const BuildSubjectOptions& options, std::FILE* out);

}  // namespace skinstream::cli
