#pragma once
// A whole file's bytes, for the readers that parse from memory (TRC, meshes, marker sets, point
// caches, PNG, MakeHuman's JSON). Problems come as one-line FileErrors: "cannot open", "read
// failed", or a file larger than the reader accepts ("is N bytes, too large for a marker set"),
// refused before anything is read.
#include <cstdint>
#include <limits>
#include <string>

namespace skinstream {

struct WholeFileLimit {
  std::uintmax_t max_bytes = std::numeric_limits<std::uintmax_t>::max();
  const char* kind = "file";  // names the file in the error: "too large for a <kind>"
};

std::string read_whole_file(const std::string& path, WholeFileLimit limit = {});  // throws FileError

}  // namespace skinstream
