// Stanford PLY meshes, through both readers (mesh_file's ASCII and binary one, and mesh_ply's
// for the generator's own files): any bytes are read or refused with a one-line FileError; a
// mesh read has only in-range face indices.
#include <cstdlib>

#include "fuzz/fuzz_input_file.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/mesh_file.h"
#include "protocol/mesh_ply.h"

namespace {

// Every corner names a vertex (a mesh_ply face's fourth is -1 for a triangle).
template <typename Faces>
void expect_indices_in_range(const Faces& faces, size_t vertex_count, bool last_may_be_absent) {
  for (const auto& face : faces)
    for (size_t k = 0; k < face.size(); ++k)
      if (!(last_may_be_absent && k == 3 && face[k] == -1) && (face[k] < 0 || static_cast<size_t>(face[k]) >= vertex_count))
        std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skinstream::fuzz::write_input_file(data, size, ".ply");
  skinstream::fuzz::expect_result_or_file_error([&] {
    const skinstream::TriangleMesh mesh = skinstream::read_mesh(path);
    expect_indices_in_range(mesh.faces, mesh.vertices.size(), false);
  });
  skinstream::fuzz::expect_result_or_file_error([&] {
    const skinstream::PlyMesh mesh = skinstream::read_ply(path);
    expect_indices_in_range(mesh.faces, mesh.vertices.size(), true);
  });
  return 0;
}
