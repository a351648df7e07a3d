// C3D files: any bytes are read as a capture or refused with a one-line FileError; nothing else
// (no other exception, no out-of-bounds read, no undefined behaviour).
#include "fuzz/fuzz_input_file.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/c3d.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skinstream::fuzz::write_input_file(data, size, ".c3d");
  skinstream::fuzz::expect_capture_or_file_error([&] { return skinstream::read_c3d(path); });
  return 0;
}
