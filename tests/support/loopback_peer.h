#pragma once
// Raw loopback peers for end-to-end tests: a TCP connection from a chosen 127.x address (so one
// machine can play several subscriber hosts) and an HTTP GET with a deadline.
#include <chrono>
#include <functional>
#include <string>

#include "support/eventually.h"  // the end-to-end tests wait with it too

namespace skinstream::test {

// A TCP connection to 127.0.0.1:`port` from `from` (any 127.x address; "" = the system's), or
// -1. `receive_buffer_bytes` > 0 sets SO_RCVBUF before connecting (a peer that reads nothing
// then stops the sender's writes early). Connected even before the server accepts it.
int connect_loopback(int port, const std::string& from = "", int receive_buffer_bytes = 0);

// `request` (a whole HTTP request) over a new connection, waiting at most `limit` for the whole
// reply; "" when none came.
std::string http_exchange_within(int port, const std::string& request, std::chrono::seconds limit, const std::string& from = "");
// GET `target` with Connection: close.
std::string http_get_within(int port, const std::string& target, std::chrono::seconds limit);

}  // namespace skinstream::test
