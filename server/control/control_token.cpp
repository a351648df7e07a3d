#include "server/control/control_token.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "protocol/files/file_error.h"

namespace skinstream::server {
namespace {

constexpr size_t kMaxControlTokenFileBytes = 4096;

std::string read_control_token_file(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) throw FileError(path, "cannot read the control token file");
  if (!S_ISREG(status.st_mode)) throw FileError(path, "the control token file is not a regular file");
  if (status.st_mode & S_IROTH)
    throw FileError(path,
                    "the control token file is readable by every user: chmod 600 it (the token is a secret)");
  if (status.st_size > static_cast<off_t>(kMaxControlTokenFileBytes))
    throw FileError(path, "the control token file is over " + std::to_string(kMaxControlTokenFileBytes) +
                              " bytes: it holds the token on its first line");
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!in || !std::getline(in, line))
    throw FileError(path, "cannot read the control token file, or it is empty");
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
  if (const std::string problem = control_token_problem(line); !problem.empty())
    throw FileError(path, "the control token on the first line " + problem);
  return line;
}

}  // namespace

std::string control_token_problem(std::string_view token) {
  if (token.size() < kMinControlTokenBytes || token.size() > kMaxControlTokenBytes)
    return "must be " + std::to_string(kMinControlTokenBytes) + "-" + std::to_string(kMaxControlTokenBytes) +
           " bytes (it is " + std::to_string(token.size()) + ")";
  if (!std::all_of(token.begin(), token.end(), [](char c) { return c > 0x20 && c < 0x7f; }))
    return "must be visible ASCII characters only (no spaces)";
  return "";
}

std::optional<std::string> load_control_token(const std::string& token_file, const char* variable_value) {
  const bool from_variable = variable_value != nullptr && *variable_value != '\0';
  if (!token_file.empty() && from_variable)
    throw ConfigError(std::string("control token given twice: control_token_file and ") +
                      kControlTokenVariable + "; give one");
  if (!token_file.empty()) return read_control_token_file(token_file);
  if (!from_variable) return std::nullopt;
  if (const std::string problem = control_token_problem(variable_value); !problem.empty())
    throw ConfigError(std::string(kControlTokenVariable) + ": the control token " + problem);
  return std::string(variable_value);
}

std::optional<std::string> load_control_token(const DaemonConfig& config) {
  return load_control_token(config.control_token_file, std::getenv(kControlTokenVariable));
}

}  // namespace skinstream::server
