#pragma once
// Binary little-endian PLY for meshes (the generator's per-frame truth meshes): float x y z per
// vertex, faces as polygons (uchar count, int indices). Millimetres, as given.
#include <string>
#include <string_view>
#include <vector>

#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

// Throws FileError when the file cannot be written or a face index is out of range.
void write_ply(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<Face>& faces);

// Reads back what write_ply writes (binary little-endian, float vertices, uchar/int faces).
struct PlyMesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
};
PlyMesh read_ply(const std::string& path);
// The same from a whole file's bytes in memory; `name` stands for the path in errors.
PlyMesh read_ply_bytes(std::string_view bytes, const std::string& name);

}  // namespace skinstream
