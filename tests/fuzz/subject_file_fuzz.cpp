// Subject files: any bytes are read as a subject or refused with a one-line FileError. The
// payload's CRC would refuse nearly every mutation before the decoder saw it, so an input of odd
// length gets a payload size and CRC that agree with it (as a writer's file would) and the
// decoder itself is fuzzed; one of even length is read as it is.
#include <cstring>
#include <vector>

#include "fuzz/fuzz_input_file.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/byte_buffer.h"
#include "protocol/subject_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<unsigned char> file(data, data + size);
  constexpr size_t kHeaderBytes = 20, kCrcBytes = 4;  // magic 8, version 4, payload size 8 | payload | CRC
  if ((size & 1) && file.size() >= kHeaderBytes + kCrcBytes) {
    const uint64_t payload = file.size() - kHeaderBytes - kCrcBytes;
    std::memcpy(file.data() + 12, &payload, 8);
    const uint32_t crc = skinstream::crc32(file.data() + kHeaderBytes, payload);
    std::memcpy(file.data() + file.size() - kCrcBytes, &crc, 4);
  }
  const std::string path = skinstream::fuzz::write_input_file(file.data(), file.size(), ".sks");
  skinstream::fuzz::expect_result_or_file_error([&] { return skinstream::read_subject_file(path); });
  return 0;
}
