// TRC files: any bytes are read as a capture or refused with a one-line FileError. Read from
// memory; one input in 16 also through a file, with the same result (fuzz/fuzz_input_file.h).
#include <string_view>

#include "fuzz/fuzz_input_file.h"
#include "protocol/files/trc.h"

namespace fuzz = skinstream::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto from_memory = fuzz::outcome([&] { return skinstream::read_trc_bytes(text, "input.trc"); });
  if (from_memory) fuzz::expect_consistent(*from_memory);
  if (fuzz::also_through_a_file(size)) {
    const std::string path = fuzz::write_input_file(data, size, ".trc");
    fuzz::expect_agreement(from_memory, fuzz::outcome([&] { return skinstream::read_trc(path); }), fuzz::same_capture);
  }
  return 0;
}
