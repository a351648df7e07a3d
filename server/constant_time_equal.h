#pragma once
// Compares a secret (a token) with what a peer sent in time that does not depend on where, or
// whether, their bytes differ: no early exit on the length or the content, so a peer cannot find
// the token byte by byte by timing its refusals.

#include <string_view>

namespace skinstream::server {

bool constant_time_equal(std::string_view a, std::string_view b);

}  // namespace skinstream::server
