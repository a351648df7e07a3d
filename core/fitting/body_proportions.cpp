#include "core/fitting/body_proportions.h"

#include <cmath>
#include <stdexcept>

namespace skinstream {

BodyProportions BodyProportions::neutral(const TemplateSegments& segments) {
  BodyProportions p;
  p.length.assign(segments.shape_groups.size(), 1.0);
  p.girth.assign(segments.shape_groups.size(), 1.0);
  return p;
}

std::vector<BoneMap> proportion_bones(const Skeleton& skeleton, const TemplateSegments& segments,
                                      const BodyProportions& proportions) {
  const size_t groups = segments.shape_groups.size();
  if (proportions.length.size() != groups || proportions.girth.size() != groups)
    throw std::invalid_argument("body proportions: " + std::to_string(proportions.length.size()) + " lengths and " +
                                std::to_string(proportions.girth.size()) + " girths for " + std::to_string(groups) +
                                " shape groups");
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(proportions.overall)) throw std::invalid_argument("body proportions: the overall scale is not positive");
  for (size_t g = 0; g < groups; ++g)
    if (!positive(proportions.length[g]) || !positive(proportions.girth[g]))
      throw std::invalid_argument("body proportions: a scale of " + segments.shape_groups[g] + " is not positive");
  std::vector<BoneMap> maps(static_cast<size_t>(skeleton.size()));
  for (int b = 0; b < skeleton.size(); ++b) {
    const Bone& bone = skeleton.bone(b);
    const int group = segments.segments[static_cast<size_t>(segments.bone_segment[static_cast<size_t>(b)])].shape_group;
    const double length = bone.length();
    const Vec3 axis = length > 0.0 ? Vec3((bone.tail - bone.head) / length) : Vec3::UnitZ();
    const Eigen::Matrix3d along = axis * axis.transpose();
    const Eigen::Matrix3d stretch =
        proportions.overall * (proportions.length[group] * along + proportions.girth[group] * (Eigen::Matrix3d::Identity() - along));
    const Vec3 head = bone.parent < 0 ? bone.head : Vec3(maps[static_cast<size_t>(bone.parent)] * bone.head.homogeneous());
    maps[b].leftCols<3>() = stretch;
    maps[b].col(3) = head - stretch * bone.head;
  }
  return maps;
}

Vec3 proportioned_vertex(const Vec3& rest, const SkinWeights& weights, int vertex, const std::vector<BoneMap>& maps) {
  BoneMap blended = BoneMap::Zero();
  for (int k = weights.begin(vertex); k < weights.end(vertex); ++k)
    blended += weights.weights[static_cast<size_t>(k)] * maps[static_cast<size_t>(weights.bones[static_cast<size_t>(k)])];
  return blended * rest.homogeneous();
}

std::vector<Vec3> proportioned_vertices(const std::vector<Vec3>& rest, const SkinWeights& weights,
                                        const std::vector<BoneMap>& maps) {
  if (weights.vertex_count() != static_cast<int>(rest.size()))
    throw std::invalid_argument("proportioned_vertices: " + std::to_string(weights.vertex_count()) + " weight rows for " +
                                std::to_string(rest.size()) + " vertices");
  std::vector<Vec3> out(rest.size());
  for (size_t v = 0; v < rest.size(); ++v) out[v] = proportioned_vertex(rest[v], weights, static_cast<int>(v), maps);
  return out;
}

std::vector<Vec3> proportioned_pivots(const Skeleton& skeleton, const TemplateSegments& segments,
                                      const std::vector<BoneMap>& maps) {
  std::vector<Vec3> out;
  for (const TemplateSegment& s : segments.segments)
    out.push_back(maps[static_cast<size_t>(s.first_bone)] * skeleton.bone(s.first_bone).head.homogeneous());
  return out;
}

}  // namespace skinstream
