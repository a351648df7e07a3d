// C3D files: any bytes are read as a capture or refused with a one-line FileError; nothing else
// (no other exception, no out-of-bounds read, no undefined behaviour). Read from memory; one
// input in 16 also through a file, with the same result (fuzz/fuzz_input_file.h).
#include "fuzz/fuzz_input_file.h"
#include "protocol/files/c3d.h"

namespace fuzz = skinstream::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto from_memory = fuzz::outcome([&] { return skinstream::read_c3d_bytes({data, size}, "input.c3d"); });
  if (from_memory) fuzz::expect_consistent(*from_memory);
  if (fuzz::also_through_a_file(size)) {
    const std::string path = fuzz::write_input_file(data, size, ".c3d");
    fuzz::expect_agreement(from_memory, fuzz::outcome([&] { return skinstream::read_c3d(path); }), fuzz::same_capture);
  }
  return 0;
}
