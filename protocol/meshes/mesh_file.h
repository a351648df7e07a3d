#pragma once
// Triangle meshes from and to Wavefront OBJ and Stanford PLY (ASCII, binary little- and
// big-endian). Vertex order is kept exactly as in the file (vertex i of the file is vertex i
// here: the deformation indexes vertices by position in the file), no vertex is merged, added
// or dropped, and polygons are fanned into triangles (v0 v1 v2, v0 v2 v3, ...).
//
// The readers are strict: a file that is truncated, has trailing bytes (binary PLY), a line
// that does not parse, a face index out of range, no faces, or a non-finite coordinate is
// rejected with a FileError naming the file. (OpenMesh's readers were tried first and found
// to accept such files silently: its OBJ reader drops unparsable "v" lines and so shifts every
// later vertex index, and its PLY reader invents data for truncated ASCII files and ignores
// trailing bytes and wrong list counts in binary ones.)
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct TriangleMesh {
  std::vector<Vec3> vertices;                // file units, file order
  std::vector<std::array<int, 3>> faces;     // 0-based, polygons fanned, winding as in the file
};

// Reads .obj or .ply (extension, case-insensitive). Throws FileError.
TriangleMesh read_mesh(const std::string& path);
// The same from a whole file's bytes in memory; `name`'s extension says the format, and it stands
// for the path in errors.
TriangleMesh read_mesh_bytes(std::string_view bytes, const std::string& name);

// Wavefront OBJ with one "v" line per vertex (full double precision) and 1-based "f" lines.
// With normals (one per vertex), "vn" lines are written and faces reference them (f a//a ...).
// Throws FileError for a face index out of range, a normals count that does not match, or a
// file that cannot be written.
void write_obj(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<std::array<int, 3>>& faces, const std::vector<Vec3>* normals = nullptr);
void write_obj(const std::string& path, const TriangleMesh& mesh);

// Binary little-endian PLY of triangles, written by protocol/meshes/mesh_ply.h (float coordinates).
void write_ply(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<std::array<int, 3>>& faces);
void write_ply(const std::string& path, const TriangleMesh& mesh);

}  // namespace skinstream
