#pragma once
// A skinned body: rest-pose surface (quads and triangles), its skeleton and skin weights.
// Units and axes as in skeleton.h: millimetres, Z up, facing +Y, left on -X.
#include <utility>
#include <vector>

#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"
#include "core/body/skeleton.h"

namespace skinstream {

// Per-vertex bone weights in compressed rows: vertex v has entries [offsets[v], offsets[v+1]).
struct SkinWeights {
  std::vector<int> offsets{0};
  std::vector<int> bones;
  std::vector<double> weights;

  int vertex_count() const { return static_cast<int>(offsets.size()) - 1; }
  int begin(int v) const { return offsets[static_cast<size_t>(v)]; }
  int end(int v) const { return offsets[static_cast<size_t>(v) + 1]; }
  double weight(int v, int bone) const;  // 0 when the bone does not influence v
  int dominant(int v) const;             // bone with the largest weight

  // From per-vertex (bone, weight) lists: drops weights <= 1e-6, merges duplicate bones and
  // normalises each vertex to sum 1. Throws std::invalid_argument for a vertex with no positive
  // weight, a negative or non-finite weight, or a bone outside [0, bone_count).
  static SkinWeights from_lists(const std::vector<std::vector<std::pair<int, double>>>& lists,
                                int bone_count);
};

struct Body {
  std::vector<Vec3> rest;  // vertex positions, mm
  std::vector<Face> faces;
  Skeleton skeleton;
  SkinWeights weights;  // one row per vertex

  int vertex_count() const { return static_cast<int>(rest.size()); }
};

// Throws std::invalid_argument naming the first problem: no vertices, a non-finite vertex,
// a face index out of range or repeated in a face, weights not one row per vertex, a bone
// index outside the skeleton.
void validate(const Body& body);

}  // namespace skinstream
