#pragma once
// The file readers take a path: a fuzz input is written to one scratch file per process, in
// $TMPDIR (scripts/fuzz.sh points it into build-fuzz/), then read back by the reader.
#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstdint>
#include <fstream>
#include <string>

namespace skinstream::fuzz {

inline std::string write_input_file(const uint8_t* data, size_t size, const std::string& extension) {
  const char* folder = std::getenv("TMPDIR");
  const std::string path = std::string(folder && *folder ? folder : "/tmp") + "/skinstream_fuzz_" + std::to_string(getpid()) + extension;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace skinstream::fuzz
