#pragma once
// Paths to the real test data: the shared captures and a scratch folder in the build tree.
#include <string>

namespace skinstream::test {
std::string shared_path(const std::string& relative);  // ../shared/<relative>
std::string source_path(const std::string& relative);  // project source tree
std::string scratch_path(const std::string& name);     // build/test_tmp/<pid>/<name>, folder created
}  // namespace skinstream::test
