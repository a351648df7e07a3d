#pragma once
// Triangle meshes: the faces of a surface, its normals, closest points and enclosed volume.
// Shared by the subject builders (core/offline), the synthetic bodies (core/synth) and the mesh
// files.
#include <array>
#include <vector>

#include "core/capture.h"

namespace skinstream {

// A polygon of the surface: a quad (a, b, c, d) counter-clockwise seen from outside, or a
// triangle with d == -1.
using Face = std::array<int, 4>;
using Triangle = std::array<int, 3>;

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

// Whether triangles (a0, a1, a2) and (b0, b1, b2) cross each other: an edge of one passes
// through the interior of the other. Touching (a vertex or an edge on the other triangle, to
// within 1e-10 of their extent) and coplanar overlaps do not count: a surface passing through
// itself crosses.
bool triangles_cross(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2);

// Signed volume enclosed by a closed triangle surface (positive when faces point outward).
double signed_volume(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles);

}  // namespace skinstream
