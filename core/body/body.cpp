#include "core/body/body.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace skinstream {

double SkinWeights::weight(int v, int bone) const {
  for (int k = begin(v); k < end(v); ++k)
    if (bones[static_cast<size_t>(k)] == bone) return weights[static_cast<size_t>(k)];
  return 0.0;
}

int SkinWeights::dominant(int v) const {
  int best = -1;
  double w = -1.0;
  for (int k = begin(v); k < end(v); ++k)
    if (weights[static_cast<size_t>(k)] > w) {
      w = weights[static_cast<size_t>(k)];
      best = bones[static_cast<size_t>(k)];
    }
  return best;
}

SkinWeights SkinWeights::from_lists(const std::vector<std::vector<std::pair<int, double>>>& lists,
                                    int bone_count) {
  SkinWeights out;
  out.offsets.reserve(lists.size() + 1);
  for (size_t v = 0; v < lists.size(); ++v) {
    std::vector<std::pair<int, double>> row;
    for (const auto& [bone, w] : lists[v]) {
      if (bone < 0 || bone >= bone_count)
        throw std::invalid_argument("skin weights: vertex " + std::to_string(v) + " names bone " +
                                    std::to_string(bone) + " of " + std::to_string(bone_count));
      if (!std::isfinite(w) || w < 0.0)
        throw std::invalid_argument("skin weights: vertex " + std::to_string(v) + " has weight " +
                                    std::to_string(w));
      if (w <= 1e-6) continue;
      // The bone by value: clang 14 cannot capture a structured binding.
      auto it = std::find_if(row.begin(), row.end(), [b = bone](const auto& e) { return e.first == b; });
      if (it != row.end())
        it->second += w;
      else
        row.emplace_back(bone, w);
    }
    double sum = 0.0;
    for (const auto& e : row) sum += e.second;
    if (row.empty() || sum <= 0.0)
      throw std::invalid_argument("skin weights: vertex " + std::to_string(v) + " has no weight");
    std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [bone, w] : row) {
      out.bones.push_back(bone);
      out.weights.push_back(w / sum);
    }
    out.offsets.push_back(static_cast<int>(out.bones.size()));
  }
  return out;
}

void validate(const Body& body) {
  const int n = body.vertex_count();
  if (n == 0) throw std::invalid_argument("body: no vertices");
  for (int v = 0; v < n; ++v)
    if (!body.rest[static_cast<size_t>(v)].allFinite())
      throw std::invalid_argument("body: vertex " + std::to_string(v) + " is not finite");
  if (body.faces.empty()) throw std::invalid_argument("body: no faces");
  for (size_t f = 0; f < body.faces.size(); ++f) {
    const Face& face = body.faces[f];
    const int corners = face[3] < 0 ? 3 : 4;
    for (int i = 0; i < corners; ++i) {
      if (face[static_cast<size_t>(i)] < 0 || face[static_cast<size_t>(i)] >= n)
        throw std::invalid_argument("body: face " + std::to_string(f) + " has vertex " +
                                    std::to_string(face[static_cast<size_t>(i)]) + " of " +
                                    std::to_string(n));
      for (int j = 0; j < i; ++j)
        if (face[static_cast<size_t>(i)] == face[static_cast<size_t>(j)])
          throw std::invalid_argument("body: face " + std::to_string(f) + " repeats a vertex");
    }
  }
  if (body.weights.vertex_count() != n)
    throw std::invalid_argument("body: " + std::to_string(body.weights.vertex_count()) + " weight rows for " +
                                std::to_string(n) + " vertices");
  if (body.skeleton.empty()) throw std::invalid_argument("body: no skeleton");
  for (int b : body.weights.bones)
    if (b < 0 || b >= body.skeleton.size())
      throw std::invalid_argument("body: weight names bone " + std::to_string(b) + " of " +
                                  std::to_string(body.skeleton.size()));
}

}  // namespace skinstream
