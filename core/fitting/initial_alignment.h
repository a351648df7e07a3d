#pragma once
// The first guess of where the template stands in the capture, before any joint turns: a
// similarity (rotation, translation, scale) of the template's rest pose onto one frame's markers.
// With named markers it is the closed-form fit of their defined places to where they are
// (trunk and head markers only when there are enough: arms and legs are not posed yet). With
// none, the capture's up axis and the actor's facing are unknown too: every axis-aligned up
// direction and twelve headings are tried, each refined by iterated closest points to the
// template's surface, and the one whose markers lie closest to the surface wins.

#include <span>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

struct Similarity {
  RigidTransform rigid;  // applied after the scale
  double scale = 1.0;
  Vec3 apply(const Vec3& p) const { return rigid.apply(scale * p); }
};

// Template points (rest pose, mm) and the same markers measured; pairs with a non-finite
// measurement are skipped. Throws std::invalid_argument with fewer than 3 usable pairs.
Similarity align_named(std::span<const Vec3> template_points, std::span<const Vec3> measured);

struct BlindAlignment {
  Similarity similarity;
  double median_distance_mm = 0.0;  // of the markers to the aligned surface
};

// Markers with no names: the search above, for each up direction in `ups` (all six axis
// directions when empty), best first. `markers`: one frame, non-finite ones skipped (at least 4
// needed); the template's rest vertices and triangles.
std::vector<BlindAlignment> align_blind(std::span<const Vec3> rest_vertices, std::span<const Triangle> triangles,
                                        std::span<const Vec3> markers, std::span<const Vec3> ups = {});

// The capture's up direction from how its markers move: the axis direction along which each
// frame's lowest marker stays most level over the take (feet on the floor), when it is clearly
// more level than along any other axis; empty otherwise (too few frames, or no floor to tell).
// frames: frame_count x marker_count, frame-major, non-finite = missing.
std::vector<Vec3> capture_up(std::span<const Vec3> frames, int frame_count, int marker_count);

}  // namespace skinstream
