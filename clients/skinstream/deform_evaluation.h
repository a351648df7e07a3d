#pragma once
// Section 5 judged against the synthetic ground truth, side by side: the detailed mesh deformed
// from the markers by rigid parts only, quadratic without residual, rigid with RBF residual, the
// full method (quadratic + RBF), and conventional linear blend skinning driven by a sparse
// marker set (the paper's Figures 7 and 8), each compared with the generator's true mesh. LBS
// runs twice: with weights computed from the rest mesh and skeleton alone (bone heat, as a
// rigging tool would), and with the very weights the truth is skinned with (an oracle: no
// conventional pipeline has them).
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "clients/skinstream/weight_rule_flags.h"
#include "core/baselines/segment_skinning.h"
#include "core/deform/deformation_model.h"
#include "core/offline/deformation_builder.h"
#include "core/subject_model.h"
#include "core/synth/conventional_marker_set.h"
#include "core/synth/synth_capture.h"

namespace skinstream::cli {

struct DeformEvaluationOptions {
  int frame_stride = 4;          // evaluate every Nth frame
  double marker_offset_mm = 4.0;  // the generator's markers sit this far above the skin
  // The vertex error is reported over the vertices the markers cover (within this distance of
  // the reference marker surface) and, separately, over all vertices.
  double covered_reach_mm = 30.0;
  std::string render_dir;        // when set: PNGs of a few frames, every method side by side
  int render_frames = 3;
  // false: the deformation uses the truth skin of the reference frame as the detailed model
  // (already registered: the table then measures sections 5.2-5.3 alone); registration is still
  // run and reported on its own. true: the deformation uses the registered artist's model.
  bool deform_registered_mesh = false;
  WeightRuleFlags weight_rules;  // the weight rules beyond the paper's, all on by default
  std::string part_file;        // a user's parts ({"marker name": part}) instead of mean shift
};

// Everything built once from the range-of-motion take: the subject (section 4), the detailed
// mesh registered and segmented (section 5.1-5.2), and the conventional marker set.
struct DeformationSetup {
  SubjectModel subject;
  DeformationModel deformation;
  DeformationBuildReport build;
  RegistrationReport registration;        // the artist's model registered to the markers
  double registration_vertex_error_mm = 0;  // mean |registered vertex - truth vertex|, reference frame
  synth::ConventionalMarkerSet conventional;  // its skinning: the truth's weights (the oracle)
  SegmentSkinningModel conventional_heat;     // the same markers, bone heat weights
  std::vector<int> subject_to_truth;  // subject marker -> truth channel
  double build_seconds = 0.0;
};

// `body` is the generator's body (subdivided to match `training` when it is); the artist's
// model given to registration is the skin-only truth mesh of the subject's reference frame.
DeformationSetup prepare_deformation(const Body& body, const synth::SynthCapture& training,
                                     const DeformEvaluationOptions& options);

nlohmann::ordered_json evaluate_deformation(const DeformationSetup& setup, const synth::SynthCapture& take,
                                            const std::string& motion, const DeformEvaluationOptions& options);

// The table's acceptance rule over evaluate_deformation's takes: the full method has the lowest
// vertex mean and the lowest vertex p95 of every row that is not an oracle, on every take.
// Maxima are not part of it; each take's lowest maximum is reported with where the full
// method's maximum occurs (vertex, frame, nearest marker).
nlohmann::ordered_json judge_table_rule(const nlohmann::ordered_json& takes);

}  // namespace skinstream::cli
