// Subject files: any bytes are read as a subject or refused with a one-line FileError. The
// payload's CRC would refuse nearly every mutation before the decoder saw it, so an input of odd
// length gets a payload size and CRC that agree with it (as a writer's file would) and the
// decoder itself is fuzzed; one of even length is read as it is. Read from memory; one input in
// 16 also through a file, with the same result (fuzz/fuzz_input_file.h).
#include <cstring>
#include <vector>

#include "fuzz/fuzz_input_file.h"
#include "protocol/byte_buffer.h"
#include "protocol/files/subject_file.h"

namespace fuzz = skinstream::fuzz;
using skinstream::SubjectFile;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<unsigned char> file(data, data + size);
  constexpr size_t kHeaderBytes = 20, kCrcBytes = 4;  // magic 8, version 4, payload size 8 | payload | CRC
  if ((size & 1) && file.size() >= kHeaderBytes + kCrcBytes) {
    const uint64_t payload = file.size() - kHeaderBytes - kCrcBytes;
    std::memcpy(file.data() + 12, &payload, 8);
    const uint32_t crc = skinstream::crc32(file.data() + kHeaderBytes, payload);
    std::memcpy(file.data() + file.size() - kCrcBytes, &crc, 4);
  }
  const auto from_memory = fuzz::outcome([&] { return skinstream::read_subject_bytes(file, "input.sks"); });
  if (fuzz::also_through_a_file(size)) {
    const std::string path = fuzz::write_input_file(file.data(), file.size(), ".sks");
    // A subject has no equality; both read it with the same counts, or both refused it.
    fuzz::expect_agreement(from_memory, fuzz::outcome([&] { return skinstream::read_subject_file(path); }),
                           [](const SubjectFile& a, const SubjectFile& b) {
                             return a.model.marker_count() == b.model.marker_count() && a.deformation.has_value() == b.deformation.has_value();
                           });
  }
  return 0;
}
