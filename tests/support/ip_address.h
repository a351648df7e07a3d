#pragma once
// An address written as text, for tables of addresses in tests.
#include "server/asio.h"

namespace skinstream::test {

inline boost::asio::ip::address ip(const char* text) { return boost::asio::ip::make_address(text); }

}  // namespace skinstream::test
