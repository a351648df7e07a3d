// Wavefront OBJ meshes: any bytes are read as a mesh or refused with a one-line FileError; a
// mesh read has only in-range face indices. Read from memory; one input in 16 also through a
// file, with the same result (fuzz/fuzz_input_file.h).
#include <cstdlib>
#include <string_view>

#include "fuzz/fuzz_input_file.h"
#include "protocol/meshes/mesh_file.h"

namespace fuzz = skinstream::fuzz;
using skinstream::TriangleMesh;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto from_memory = fuzz::outcome([&] { return skinstream::read_mesh_bytes(bytes, "input.obj"); });
  if (from_memory)
    for (const auto& face : from_memory->faces)
      for (const int v : face)
        if (v < 0 || static_cast<size_t>(v) >= from_memory->vertices.size()) std::abort();
  if (fuzz::also_through_a_file(size)) {
    const std::string path = fuzz::write_input_file(data, size, ".obj");
    fuzz::expect_agreement(from_memory, fuzz::outcome([&] { return skinstream::read_mesh(path); }), fuzz::same_mesh<TriangleMesh>);
  }
  return 0;
}
