#pragma once
// The control API's token (docs/control-api.md): read from the file control_token_file names, or
// from the environment variable SKINSTREAM_CONTROL_TOKEN, never from the command line (where ps
// shows it to every user). A token file any user may read is refused: the token would be no
// secret. Errors are one line and never hold the token.

#include <optional>
#include <string>
#include <string_view>

#include "server/config.h"

namespace skinstream::server {

inline constexpr const char* kControlTokenVariable = "SKINSTREAM_CONTROL_TOKEN";
inline constexpr size_t kMinControlTokenBytes = 16;
inline constexpr size_t kMaxControlTokenBytes = 256;

// The token, or nullopt when none is given (the control API is then off). Throws FileError (the
// file cannot be read, is readable by every user, holds no good token) or ConfigError (the
// variable's token is not good, or both the file and the variable are given).
std::optional<std::string> load_control_token(const DaemonConfig& config);
// The same with the variable's value given (nullptr: not set).
std::optional<std::string> load_control_token(const std::string& token_file, const char* variable_value);

// "" or what is wrong with a token: 16-256 bytes of visible ASCII (it travels in an HTTP header).
std::string control_token_problem(std::string_view token);

}  // namespace skinstream::server
