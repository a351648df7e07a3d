#pragma once
// A parameter of a request target's query ("/stream?token=a%2Fb" -> "a/b" for "token"), with
// %XX escapes decoded. nullopt when the parameter is absent or an escape is malformed.

#include <optional>
#include <string>
#include <string_view>

namespace skinstream::server {

std::optional<std::string> query_parameter(std::string_view target, std::string_view name);

}  // namespace skinstream::server
