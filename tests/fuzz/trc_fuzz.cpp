// TRC files: any bytes are read as a capture or refused with a one-line FileError.
#include "fuzz/fuzz_input_file.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/trc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = skinstream::fuzz::write_input_file(data, size, ".trc");
  skinstream::fuzz::expect_capture_or_file_error([&] { return skinstream::read_trc(path); });
  return 0;
}
