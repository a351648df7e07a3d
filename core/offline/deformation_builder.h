#pragma once
// Raw detailed mesh + training take -> DeformationModel (section 5.1-5.2), offline and once per
// subject: registers the mesh to the reference marker surface, segments the marker surface into
// near-rigid parts, weighs the markers (alpha) and the vertices (beta).

#include <array>
#include <span>
#include <vector>

#include "core/deform/deformation_model.h"
#include "core/offline/fold_weight_smoothing.h"
#include "core/offline/marker_part_weights.h"
#include "core/offline/mesh_registration.h"
#include "core/offline/part_joints.h"
#include "core/offline/part_segmentation.h"
#include "core/offline/quadratic_ridge_selection.h"
#include "core/offline/rbf_ridge_selection.h"
#include "core/subject_model.h"

namespace skinstream {

struct DeformationBuildOptions {
  bool register_mesh = true;  // false: the mesh is already registered (used as given)
  RegistrationOptions registration;
  std::vector<RegistrationLandmark> landmarks;  // empty: guess_landmarks (mesh close to the markers)
  LandmarkGuessOptions landmark_guess;
  SegmentationOptions segmentation;
  std::vector<int> part_assignment;  // a user's parts (per marker or per triangle); empty: mean shift
  AssignmentKind assignment_kind = AssignmentKind::PerMarker;
  MarkerWeightOptions weights;
  bool split_at_joints = true;  // false: no split of the vertex weights at hinge joints
  bool blend_at_joints = true;  // false: the split is a hard switch at the plane (no ramp)
  bool blend_folds = true;      // false: no blend across folds (both false: the paper's rule alone)
  bool smooth_folds = true;     // false: the fold blend's weights as they are (fold_weight_smoothing.h)
  FoldSmoothingOptions fold_smoothing{-1.0};  // band_mm < 0: half the median nearest-marker distance
  PartJointOptions joints;
};

struct DeformationBuildReport {
  bool registered = false;
  int landmarks = 0;
  RegistrationReport registration;
  int parts = 0;
  int mean_shift_groups = 0;
  double max_part_rigid_rms_mm = 0.0;
  std::vector<int> part_triangles;         // marker-surface triangles per part
  std::vector<double> part_rigid_rms_mm;   // per part, over the training take (PartSegmentation)
  std::vector<int> marker_part;            // each marker's main part (marker_parts): a part file's content
  std::vector<int> unused_parts;           // of a user's assignment: indices that hold no triangle (dropped)
  int boundary_markers = 0;
  int markers_added_for_min_members = 0;
  double mean_influences_per_vertex = 0.0;
  int fold_smoothed_vertices = 0;  // vertices whose weights the fold smoothing re-solved
  double fold_band_mm = 0.0;       // the band around the folds smoothed with them
  std::vector<PartJoint> joints;  // the jointed part pairs the vertex weights split at
  double joint_blend_mm = 0.0;    // half-width of the ramp across their planes (0: a hard switch)
  std::vector<QuadraticRidgeChoice> part_quadratic_ridges;  // eq. 6's per part, by leave-one-out error
  std::vector<RidgeChoice> part_ridges;  // eq. 7's ridge per part, by leave-one-out error
};

// subject: the marker model (reference pose and marker surface); training: frame_count x
// markers, frame-major, all present (a filled range-of-motion take, subject order); mesh: the
// detailed surface in the reference pose (mm). Throws std::invalid_argument on unusable input.
DeformationModel build_deformation_model(const SubjectModel& subject, std::span<const Vec3> training, int frame_count,
                                         std::span<const Vec3> mesh_vertices,
                                         std::span<const std::array<int, 3>> mesh_faces,
                                         const DeformationBuildOptions& options = {},
                                         DeformationBuildReport* out_report = nullptr);

}  // namespace skinstream
