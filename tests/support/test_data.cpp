#include "support/test_data.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace skinstream::test {
std::string shared_path(const std::string& relative) { return std::string(SKINSTREAM_SHARED_DIR) + "/" + relative; }
std::string source_path(const std::string& relative) { return std::string(SKINSTREAM_SOURCE_DIR) + "/" + relative; }
// One folder per process: ctest runs every test in its own process, several at once, and two
// tests writing the same scratch name must not see each other's half-written files.
std::string scratch_path(const std::string& name) {
  static const std::string dir = std::string(SKINSTREAM_TEST_TMP_DIR) + "/" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}
std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
}  // namespace skinstream::test
