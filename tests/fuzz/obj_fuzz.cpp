// Wavefront OBJ meshes: any bytes are read as a mesh or refused with a one-line FileError; a
// mesh read has only in-range face indices.
#include <cstdlib>

#include "fuzz/fuzz_input_file.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/mesh_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skinstream::fuzz::write_input_file(data, size, ".obj");
  skinstream::fuzz::expect_result_or_file_error([&] {
    const skinstream::TriangleMesh mesh = skinstream::read_mesh(path);
    for (const auto& face : mesh.faces)
      for (const int v : face)
        if (v < 0 || static_cast<size_t>(v) >= mesh.vertices.size()) std::abort();
  });
  return 0;
}
