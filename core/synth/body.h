#pragma once
// A skinned body: rest-pose surface (quads and triangles), its skeleton and skin weights.
// Units and axes as in skeleton.h: millimetres, Z up, facing +Y, left on -X.
#include <array>
#include <utility>
#include <vector>

#include "core/capture.h"
#include "core/synth/skeleton.h"

namespace skinstream::synth {

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

// A polygon of the surface: a quad (a, b, c, d) counter-clockwise seen from outside, or a
// triangle with d == -1.
using Face = std::array<int, 4>;
using Triangle = std::array<int, 3>;

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

// Splits every quad (a,b,c,d) into (a,b,c), (a,c,d). `face_of` (optional) receives the face
// of each triangle.
std::vector<Triangle> triangulate(const std::vector<Face>& faces, std::vector<int>* face_of = nullptr);

// Area-weighted vertex normals (unit; zero for a vertex in no triangle).
std::vector<Vec3> vertex_normals(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles);

// Unit normal of a triangle (counter-clockwise = outward); zero when degenerate.
Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c);

// The closest point to p on triangle (a, b, c), with its barycentric coordinates.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Vec3* barycentric = nullptr);

// Signed volume enclosed by a closed triangle surface (positive when faces point outward).
double signed_volume(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles);

}  // namespace skinstream::synth
