#include "core/synth/subdivision.h"

#include <cstdint>
#include <map>
#include <unordered_map>

namespace skinstream::synth {

namespace {

// Accumulates weight rows of the vertices a new vertex averages.
void add_row(const SkinWeights& w, int v, double scale, std::map<int, double>& acc) {
  for (int k = w.begin(v); k < w.end(v); ++k)
    acc[w.bones[static_cast<size_t>(k)]] += scale * w.weights[static_cast<size_t>(k)];
}

}  // namespace

Body subdivide(const Body& body, std::vector<int>* parent_face) {
  validate(body);
  const int n = body.vertex_count();
  Body out;
  out.skeleton = body.skeleton;
  out.rest = body.rest;
  std::vector<std::vector<std::pair<int, double>>> rows(static_cast<size_t>(n));
  for (int v = 0; v < n; ++v)
    for (int k = body.weights.begin(v); k < body.weights.end(v); ++k)
      rows[static_cast<size_t>(v)].emplace_back(body.weights.bones[static_cast<size_t>(k)],
                                                body.weights.weights[static_cast<size_t>(k)]);

  std::unordered_map<uint64_t, int> edge_vertex;
  edge_vertex.reserve(body.faces.size() * 3);
  auto edge_point = [&](int a, int b) {
    const uint64_t key =
        (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const int id = static_cast<int>(out.rest.size());
    out.rest.push_back(0.5 * (body.rest[static_cast<size_t>(a)] + body.rest[static_cast<size_t>(b)]));
    std::map<int, double> acc;
    add_row(body.weights, a, 0.5, acc);
    add_row(body.weights, b, 0.5, acc);
    rows.emplace_back(acc.begin(), acc.end());
    edge_vertex.emplace(key, id);
    return id;
  };

  if (parent_face) parent_face->clear();
  out.faces.reserve(body.faces.size() * 4);
  for (size_t f = 0; f < body.faces.size(); ++f) {
    const Face& face = body.faces[f];
    const int k = face[3] < 0 ? 3 : 4;
    Vec3 centre = Vec3::Zero();
    std::map<int, double> acc;
    for (int i = 0; i < k; ++i) {
      centre += body.rest[static_cast<size_t>(face[static_cast<size_t>(i)])];
      add_row(body.weights, face[static_cast<size_t>(i)], 1.0 / k, acc);
    }
    const int c = static_cast<int>(out.rest.size());
    out.rest.push_back(centre / k);
    rows.emplace_back(acc.begin(), acc.end());
    int mids[4];
    for (int i = 0; i < k; ++i)
      mids[i] = edge_point(face[static_cast<size_t>(i)], face[static_cast<size_t>((i + 1) % k)]);
    for (int i = 0; i < k; ++i) {
      out.faces.push_back({face[static_cast<size_t>(i)], mids[i], c, mids[(i + k - 1) % k]});
      if (parent_face) parent_face->push_back(static_cast<int>(f));
    }
  }
  out.weights = SkinWeights::from_lists(rows, body.skeleton.size());
  return out;
}

}  // namespace skinstream::synth
