#pragma once
// The file readers are fuzzed from memory (their read_*_bytes entry points): writing every input
// to a file and reading it back held them to a few hundred inputs a second. The path readers
// share everything but the file access with them, and one input in 16 (chosen by its length, so
// a replayed input takes the same path) also goes through a scratch file, in $TMPDIR
// (scripts/fuzz.sh points it into build-fuzz/), and the path reader: both must come to the same
// result.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "core/capture.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/files/file_error.h"

namespace skinstream::fuzz {

inline bool also_through_a_file(size_t size) { return size % 16 == 1; }  // odd: the subject target fixes its CRC

inline std::string write_input_file(const uint8_t* data, size_t size, const std::string& extension) {
  const char* folder = std::getenv("TMPDIR");
  const std::string path = std::string(folder && *folder ? folder : "/tmp") + "/skinstream_fuzz_" + std::to_string(getpid()) + extension;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// What a reader made of the input: its result, or nothing when it refused it with a one-line
// FileError. Any other exception escapes and is a finding.
template <typename Read>
auto outcome(Read&& read) -> std::optional<std::invoke_result_t<Read>> {
  try {
    return read();
  } catch (const FileError& e) {
    expect_one_printable_line(e.what());
    return std::nullopt;
  }
}

// Equal to the bit (a missing sample's NaN included).
inline bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0);
}

inline bool same_capture(const Capture& a, const Capture& b) {
  return a.labels == b.labels && a.frame_count == b.frame_count && a.first_frame == b.first_frame &&
         std::memcmp(&a.rate_hz, &b.rate_hz, sizeof(double)) == 0 && same_bits(a.positions, b.positions);
}

// A TriangleMesh or PlyMesh: the same vertices to the bit and the same faces.
template <typename Mesh>
bool same_mesh(const Mesh& a, const Mesh& b) {
  return same_bits(a.vertices, b.vertices) && a.faces == b.faces;
}

// Both readers refused the input, or both read it and `same` says they agree.
template <typename Result, typename Same>
void expect_agreement(const std::optional<Result>& from_memory, const std::optional<Result>& from_file, Same&& same) {
  if (from_memory.has_value() != from_file.has_value() || (from_memory && !same(*from_memory, *from_file))) {
    std::fprintf(stderr, "the file reader and the bytes reader disagree on this input\n");
    std::abort();
  }
}

}  // namespace skinstream::fuzz
