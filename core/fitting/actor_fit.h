#pragma once
// Fits the template body to an actor from the markers of a training take, after MoSh (Loper,
// Mahmood & Black 2014) with the open MakeHuman template in place of a learned body model.
// Unknowns: the template's proportions (body_proportions.h), where each marker sits on it (a
// surface point and its height above the skin, marker_attachment.h) and the pose of its 19
// segments (template_segments.h) in the reference frame and a spread of other frames.
//
// 1. A first guess of the whole body's place (initial_alignment.h), then the reference frame's
//    pose; markers without a known place are attached where the posed surface is nearest, and
//    the two are iterated (articulated closest points).
// 2. The pose is tracked through the whole take from the reference frame, forward and back,
//    and the fit frames are chosen from it: the reference frame, then each next frame the one
//    whose pose is farthest from those chosen (a spread over the range of motion).
// 3. Rounds over the fit frames: the proportions (damped Gauss-Newton, a prior toward the
//    template's own), the poses, then each marker's place: its measured positions carried
//    back to the rest pose through its current segments' motions, their median taken, and the
//    nearest surface point to it within the marker set's allowance, with the offset the
//    distance along the normal.
// Measurements that miss by more than robust_mm pull with a constant force (Huber), so a few
// mislabelled samples cannot bend the body; a marker the fit cannot place is reported.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/body/body.h"
#include "core/deform/segment_skeleton.h"
#include "core/fitting/body_proportions.h"
#include "core/fitting/initial_alignment.h"
#include "core/fitting/marker_attachment.h"
#include "core/fitting/template_segments.h"

namespace skinstream {

// The body the fit poses: a mesh skinned by segments, and, for the template, the bones that
// proportion it. A scan made a skinned body through the template (scan_body.h) is the actor's
// own shape: it is posed and its markers placed, not proportioned.
struct FitBody {
  std::vector<Vec3> rest;  // mm, Z up, facing +Y
  std::vector<Triangle> triangles;
  VertexSegmentWeights weights;  // per vertex, over the segments
  std::vector<std::string> segment_names;
  std::vector<int> segment_parents;  // parents before children, the pelvis first
  std::vector<Vec3> rest_pivots;
  std::vector<Vec3> twist_axes;  // per segment: a limb's bone axis at rest, zero for the trunk's
  // The template's bones and segments, when the fit may proportion it (null: it may not). They
  // must outlive the FitBody.
  const Body* bones = nullptr;
  const TemplateSegments* segments = nullptr;

  int segment_count() const { return static_cast<int>(segment_names.size()); }
  int find(const std::string& name) const;  // -1 when absent
};

// The template as a fit body (proportions fitted): keeps pointers to both arguments.
FitBody fit_body_of(const Body& body, const TemplateSegments& segments);

// What the marker set says of one marker.
struct MarkerPrior {
  // The defined place (triangle < 0: none, the marker is attached where the posed template's
  // surface is nearest to it).
  MarkerAttachment place{-1};
  // The triangles the fit may move it to (empty: any); for a defined place, those within the
  // set's radius of it; for a region entry, the region's.
  std::vector<int> allowed_triangles;
};

struct ActorFitOptions {
  int fit_frames = 24;             // the reference frame and this many others at most, in all
  int rounds = 20;                 // of proportions, poses and places
  // A marker's centre above the skin (a 14 mm marker on its base: about 10 mm). Held, not
  // fitted, as MoSh does: a free height trades off against the body's girth and the place on
  // the skin, and the markers' positions alone cannot tell them apart.
  double marker_offset_mm = 10.0;
  double robust_mm = 30.0;
  // The pull of each joint toward the template's rest pose (mm^2 per rad^2, SkeletonSolverOptions
  // ::prior): while the reference frame is first posed (1 rad costs as much as one marker
  // missing by about 45 mm), then while tracking and refining (a tie-breaker for what the
  // markers do not see).
  double pose_prior = 2000.0;
  double tracking_pose_prior = 500.0;
  double twist_prior = 2000.0;  // on a limb's twist about its bone, throughout
  // Priors on the proportions (mm^2 per unit of log scale, squared): a segment group's length
  // away from the template's, and its girth away from its length (an actor is not thinner in
  // one limb than the markers show).
  double length_prior = 2e4;
  double girth_prior = 5e4;
  int track_stride = 1;  // track every n-th frame of the take (poses between are not needed)
  // Where the body stands in the reference frame, when known (a scan already brought upright and
  // facing +Y: its centre and height); otherwise from the named markers or the blind search.
  std::optional<Similarity> start;
  // Arm poses the reference frame is also fitted from, beside the rest pose, the best fit kept:
  // each turns the upper arms (left, right) to point along a direction (rest-pose axes; not
  // finite leaves that arm at rest). A scan's arms far from the rest pose's A need one: from the
  // A alone, the closest points of arms raised to a T held the template's forearm turned 81
  // degrees (the template raised to a T and fitted to its own points: 5.4 mm RMS; 1.5 from the T).
  std::vector<std::array<Vec3, 2>> arm_starts;
};

// A pose of the template's segments (local rotations relative to the parent, rest-pose axes,
// and the pelvis's translation), as SkeletonSolver keeps it.
struct SegmentPose {
  std::vector<Eigen::Matrix3d> local;
  Vec3 translation = Vec3::Zero();
};

struct ActorFit {
  BodyProportions proportions;                // empty lengths and girths when not proportioned
  std::vector<MarkerAttachment> attachments;  // one per marker
  std::vector<Vec3> rest_vertices;            // the template proportioned, in its rest pose
  std::vector<Vec3> rest_pivots;              // per segment
  VertexSegmentWeights vertex_weights;        // the template's skin weights per segment
  std::vector<int> frames;                    // the fit frames; frames[0] is the reference frame
  std::vector<SegmentPose> poses;             // per fit frame
  std::vector<Vec3> reference_vertices;       // rest_vertices posed at the reference frame
  std::vector<RigidTransform> reference_motions;  // per segment: rest pose to the reference frame
  // The runtime skeleton in the reference pose: pivots where the reference frame put them and
  // each marker's segment weights (part_segment is left for the deformation builder).
  SegmentSkeleton reference_skeleton;
  std::vector<double> marker_rms_mm;  // per marker, its miss over the fit frames (NaN: never seen)
  double rms_mm = 0.0;                // all markers over the fit frames
  int tracked_frames = 0;
  bool blind = false;                 // no marker had a defined place: the blind alignment was used
};

// body: the body to pose (fit_body_of() for the template); frames: frame_count x marker_count
// positions (mm, frame-major, non-finite = missing); priors: one per marker. Throws
// std::invalid_argument (one line) when the reference frame has too few markers to place the body.
ActorFit fit_actor(const FitBody& body, std::span<const Vec3> frames, int frame_count, int marker_count,
                   int reference_frame, std::span<const MarkerPrior> priors, const ActorFitOptions& options = {});

// The template's vertices (rest_vertices, segment weights) posed by a pose of the segments.
std::vector<Vec3> pose_vertices(const std::vector<Vec3>& rest_vertices, const VertexSegmentWeights& weights,
                                const std::vector<RigidTransform>& segment_motions);

}  // namespace skinstream
