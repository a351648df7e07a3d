#pragma once
// Where a marker sits on a body: a point of one of the template's triangles and the height of
// the marker's centre above the skin there, along the triangle's normal (MoSh's latent surface
// point plus offset; a 14 mm marker on its base sits about 10 mm up). Stored against the
// template's topology, so the same attachment holds on the template proportioned, posed or
// registered.

#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/segment_skeleton.h"
#include "core/fitting/template_segments.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

struct MarkerAttachment {
  int triangle = -1;
  Vec3 barycentric = Vec3::Constant(1.0 / 3.0);
  double offset_mm = 10.0;
};

// The skin point under the marker, on a surface with the template's triangles.
Vec3 skin_point(const MarkerAttachment& attachment, std::span<const Vec3> vertices, std::span<const Triangle> triangles);
// The marker's centre: the skin point plus the offset along the triangle's outward normal.
Vec3 attached_position(const MarkerAttachment& attachment, std::span<const Vec3> vertices,
                       std::span<const Triangle> triangles);

// The marker's share of each segment's motion: its triangle's vertices' segment weights,
// blended by its barycentric coordinates (appended to `out`, sorted by segment, summing to 1).
void attachment_segment_weights(const MarkerAttachment& attachment, std::span<const Triangle> triangles,
                                const VertexSegmentWeights& vertex_weights, std::vector<SegmentWeight>& out);

}  // namespace skinstream
