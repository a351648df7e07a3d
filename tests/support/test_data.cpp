#include "support/test_data.h"

#include <filesystem>

namespace skinstream::test {
std::string shared_path(const std::string& relative) { return std::string(SKINSTREAM_SHARED_DIR) + "/" + relative; }
std::string source_path(const std::string& relative) { return std::string(SKINSTREAM_SOURCE_DIR) + "/" + relative; }
std::string scratch_path(const std::string& name) {
  std::filesystem::create_directories(SKINSTREAM_TEST_TMP_DIR);
  return std::string(SKINSTREAM_TEST_TMP_DIR) + "/" + name;
}
}  // namespace skinstream::test
