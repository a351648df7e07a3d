#include "core/body/skinning.h"

#include <stdexcept>
#include <string>

namespace skinstream {

Eigen::Matrix<double, 3, 4> blended_transform(const SkinWeights& weights, int v,
                                              const BoneTransforms& bones) {
  Eigen::Matrix<double, 3, 4> m = Eigen::Matrix<double, 3, 4>::Zero();
  for (int k = weights.begin(v); k < weights.end(v); ++k)
    m += weights.weights[static_cast<size_t>(k)] *
         bones[static_cast<size_t>(weights.bones[static_cast<size_t>(k)])].matrix().topRows<3>();
  return m;
}

Vec3 skin_vertex(const SkinWeights& weights, int v, const Vec3& rest, const BoneTransforms& bones,
                 const Vec3* rest_normal, Vec3* normal) {
  const Eigen::Matrix<double, 3, 4> m = blended_transform(weights, v, bones);
  if (rest_normal && normal) {
    const Vec3 n = m.leftCols<3>() * *rest_normal;
    const double len = n.norm();
    *normal = len > 0.0 ? Vec3(n / len) : *rest_normal;
  }
  return m.leftCols<3>() * rest + m.col(3);
}

std::vector<Vec3> skin(const std::vector<Vec3>& rest, const SkinWeights& weights,
                       const BoneTransforms& bones) {
  if (weights.vertex_count() != static_cast<int>(rest.size()))
    throw std::invalid_argument("skin: " + std::to_string(weights.vertex_count()) + " weight rows for " +
                                std::to_string(rest.size()) + " vertices");
  for (int b : weights.bones)
    if (b < 0 || b >= static_cast<int>(bones.size()))
      throw std::invalid_argument("skin: weight names bone " + std::to_string(b) + " of " +
                                  std::to_string(bones.size()));
  std::vector<Vec3> out(rest.size());
  for (size_t v = 0; v < rest.size(); ++v) out[v] = skin_vertex(weights, static_cast<int>(v), rest[v], bones);
  return out;
}

}  // namespace skinstream
