#pragma once
// An actor's proportions on the template: each shape group's bones are stretched along their
// axis (length) and across it (girth), and the whole body is scaled. Each bone gets an affine
// map from the template's rest pose to the proportioned one, and a vertex follows its bones'
// maps blended by its skin weights, so a longer forearm carries the hand along and the skin
// between two groups stays joined.
//   map_b(x) = h'_b + overall * S_b (x - h_b),   S_b = length a a^T + girth (I - a a^T)
//   h'_root = h_root,   h'_b = map_parent(h_b)
// (h_b: the bone's head, a: its unit axis, length and girth of the bone's segment's group).

#include <Eigen/Core>
#include <vector>

#include "core/body/body.h"
#include "core/fitting/template_segments.h"

namespace skinstream {

struct BodyProportions {
  double overall = 1.0;
  std::vector<double> length;  // per shape group, 1 = the template's
  std::vector<double> girth;   // per shape group

  static BodyProportions neutral(const TemplateSegments& segments);
};

using BoneMap = Eigen::Matrix<double, 3, 4>;  // [A | t]: x -> A x + t

// One map per bone. Throws std::invalid_argument when the proportions do not have one length and
// girth per shape group, or a scale is not positive and finite.
std::vector<BoneMap> proportion_bones(const Skeleton& skeleton, const TemplateSegments& segments,
                                      const BodyProportions& proportions);

// The template's rest vertices, proportioned.
std::vector<Vec3> proportioned_vertices(const std::vector<Vec3>& rest, const SkinWeights& weights,
                                        const std::vector<BoneMap>& maps);
Vec3 proportioned_vertex(const Vec3& rest, const SkinWeights& weights, int vertex, const std::vector<BoneMap>& maps);

// Each segment's pivot (its first bone's head), proportioned.
std::vector<Vec3> proportioned_pivots(const Skeleton& skeleton, const TemplateSegments& segments,
                                      const std::vector<BoneMap>& maps);

}  // namespace skinstream
