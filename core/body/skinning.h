#pragma once
// Linear blend skinning: a vertex follows the weighted average of its bones' transforms.
#include <vector>

#include "core/body/body.h"
#include "core/body/skeleton.h"

namespace skinstream {

// The blended (generally not rigid) transform of vertex v.
Eigen::Matrix<double, 3, 4> blended_transform(const SkinWeights& weights, int v, const BoneTransforms& bones);

// Skinned position of vertex v from its rest position; its rest normal is carried along by the
// blended linear part and renormalised when `normal` is given.
Vec3 skin_vertex(const SkinWeights& weights, int v, const Vec3& rest, const BoneTransforms& bones,
                 const Vec3* rest_normal = nullptr, Vec3* normal = nullptr);

// All vertices. Throws std::invalid_argument when the sizes disagree.
std::vector<Vec3> skin(const std::vector<Vec3>& rest, const SkinWeights& weights,
                       const BoneTransforms& bones);

}  // namespace skinstream
