#include "protocol/files/whole_file.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "protocol/files/file_error.h"

namespace skinstream {

std::string read_whole_file(const std::string& path, WholeFileLimit limit) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > limit.max_bytes)
    throw FileError(path, "is " + std::to_string(size) + " bytes, too large for a " + limit.kind);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw FileError(path, "read failed");
  return std::move(text).str();
}

}  // namespace skinstream
