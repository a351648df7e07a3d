#pragma once
// Loads the CC0 MakeHuman hm08 body (../shared/data/meshes/makehuman/, see PROVENANCE.md) as a
// skinned body for the synthetic capture generator:
//   makehuman_hm08_body_only.obj  the "body" group of base.obj: 13,380 vertices, 13,378 quads
//   base.obj                      the full base mesh (19,158 vertices with helper geometry):
//                                 the skeleton's joints and the skin weights index its vertices
//   default.mhskel                skeleton (JSON): joints = mean of listed base.obj vertices
//   default_weights.mhw           skin weights (JSON): per bone, [base.obj vertex, weight]
//
// The body-only vertices are matched to base.obj by position (they are, in fact, its first
// 13,380 vertices, in order); weights on helper vertices are dropped and each vertex's weights
// renormalised. Vertex and face order of the body-only OBJ are kept.
//
// Units and axes are converted from MakeHuman's (decimetres, Y up, facing +Z, left on +X) to
// skinstream's (millimetres, Z up like Vicon captures, facing +Y, left on -X), with the soles at
// z = 0 and the midpoint of the hip joints above the origin:
//     (x, y, z)_makehuman  ->  100 * (-x, z, y) + shift
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/body/body.h"

namespace skinstream {

struct MakeHumanFiles {
  std::string body_obj, base_obj, skeleton, weights;
  // The four standard file names in `dir`.
  static MakeHumanFiles in(const std::string& dir);
};

// Throws FileError (one line naming the file) for a missing or malformed file, a body vertex
// with no match in base.obj, a bone that names an unknown joint or parent, or weights on an
// unknown bone.
Body load_makehuman(const MakeHumanFiles& files);
Body load_makehuman(const std::string& dir);

// The raw OBJ: vertices (file units, file order) and polygons (0-based; quads and triangles
// kept, larger polygons fanned). Throws FileError.
struct ObjMesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
};
ObjMesh read_obj(const std::string& path);

// For each vertex of `part`, the index of the vertex of `whole` at the same position (within
// tolerance, in the files' units); -1 when there is none. A vertex at the same index is
// preferred when several match.
std::vector<int> match_vertices(const std::vector<Vec3>& part, const std::vector<Vec3>& whole,
                                double tolerance = 1e-4);

// MakeHuman file coordinates (dm, Y up) to skinstream axes in mm, before the shift.
inline Vec3 makehuman_to_skinstream(const Vec3& p) { return 100.0 * Vec3(-p.x(), p.z(), p.y()); }

}  // namespace skinstream
