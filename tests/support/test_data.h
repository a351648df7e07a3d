#pragma once
// Paths to the real test data (the shared captures, a scratch folder in the build tree) and
// whole-file reads and writes for tests that damage files on purpose.
#include <string>

namespace skinstream::test {
std::string shared_path(const std::string& relative);  // ../shared/<relative>
std::string source_path(const std::string& relative);  // project source tree
std::string scratch_path(const std::string& name);     // build/test_tmp/<pid>/<name>, folder created
// A whole file as bytes ("" when it cannot be read), and bytes written as a whole file.
std::string read_bytes(const std::string& path);
void write_bytes(const std::string& path, const std::string& bytes);
}  // namespace skinstream::test
