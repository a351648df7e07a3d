#pragma once
// The segments a MakeHuman-style template is posed and proportioned by: 18 groups of bones that
// turn together (pelvis, abdomen, chest, head, and per side clavicle, upper arm, forearm, hand,
// thigh, shank, foot). A marker set of 37-60 markers cannot pin down the template's 163 bones
// (fingers, face, twist bones); it can pin down these. Each segment turns about the head of its
// first bone; the bones after it in the segment stay at rest relative to it. The neck turns with
// the head about the neck's base: no common marker set puts a marker on the neck, and a neck
// joint no marker sees only twists.
//
// Shape groups pair the two sides (a left and a right forearm share their proportions): actors
// are near enough symmetric, and a sparse set sees each side's segment through few markers.

#include <string>
#include <vector>

#include "core/body/body.h"
#include "core/deform/segment_skeleton.h"

namespace skinstream {

struct TemplateSegment {
  std::string name;       // e.g. "forearm.L"
  int first_bone = -1;    // the bone whose head is the segment's pivot
  int parent = -1;        // parent segment, -1 for the pelvis
  int shape_group = -1;   // index into TemplateSegments::shape_groups
};

struct TemplateSegments {
  std::vector<TemplateSegment> segments;   // parents before children, the pelvis first
  std::vector<int> bone_segment;           // per bone of the skeleton
  std::vector<std::string> shape_groups;   // "pelvis", "abdomen", "chest", "head", ..., "foot"

  int segment_count() const { return static_cast<int>(segments.size()); }
  int find(const std::string& name) const;  // -1 when absent
};

// Throws std::invalid_argument naming the first missing bone when the skeleton is not a
// MakeHuman-style one (root, spine04, spine02, neck01, clavicle, upperarm01, lowerarm01, wrist,
// upperleg01, lowerleg01, foot per side).
TemplateSegments segment_template(const Skeleton& skeleton);

// Per vertex, the skin weights summed per segment (CSR, each row sums to 1).
struct VertexSegmentWeights {
  std::vector<int> offsets{0};
  std::vector<SegmentWeight> weights;
  int vertex_count() const { return static_cast<int>(offsets.size()) - 1; }
};
VertexSegmentWeights segment_weights(const SkinWeights& weights, const TemplateSegments& segments);

}  // namespace skinstream
