// Stanford PLY meshes, through both readers (mesh_file's ASCII and binary one, and mesh_ply's
// for the generator's own files): any bytes are read or refused with a one-line FileError; a
// mesh read has only in-range face indices. Read from memory; one input in 16 also through a
// file, with the same result (fuzz/fuzz_input_file.h).
#include <cstdlib>
#include <string_view>

#include "fuzz/fuzz_input_file.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/meshes/mesh_ply.h"

namespace fuzz = skinstream::fuzz;
using skinstream::PlyMesh;
using skinstream::TriangleMesh;

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
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto mesh = fuzz::outcome([&] { return skinstream::read_mesh_bytes(bytes, "input.ply"); });
  if (mesh) expect_indices_in_range(mesh->faces, mesh->vertices.size(), false);
  const auto ply = fuzz::outcome([&] { return skinstream::read_ply_bytes(bytes, "input.ply"); });
  if (ply) expect_indices_in_range(ply->faces, ply->vertices.size(), true);
  if (fuzz::also_through_a_file(size)) {
    const std::string path = fuzz::write_input_file(data, size, ".ply");
    fuzz::expect_agreement(mesh, fuzz::outcome([&] { return skinstream::read_mesh(path); }), fuzz::same_mesh<TriangleMesh>);
    fuzz::expect_agreement(ply, fuzz::outcome([&] { return skinstream::read_ply(path); }), fuzz::same_mesh<PlyMesh>);
  }
  return 0;
}
