#pragma once
// GET /health from a running skinstreamd, for the bench and the end-to-end tests, over the plain
// HTTP exchange the bench's control requests use too (server/client/control_client.h).
#include <nlohmann/json.hpp>
#include <string>

namespace skinstream::server {

// One request over a new connection to host:http_port, read until the daemon closes it (the
// request says Connection: close). Throws boost::system::system_error when it cannot connect.
struct HttpReply {
  int status = 0;    // 0: no status line
  std::string body;  // "" when the reply has none
};
HttpReply http_exchange(const std::string& host, int http_port, const std::string& request);

// The daemon's /health JSON from host:http_port ({} when the reply has no body). Throws
// boost::system::system_error when the daemon cannot be reached, nlohmann::json::exception for a
// body that is not JSON.
nlohmann::json fetch_health(const std::string& host, int http_port);
inline nlohmann::json fetch_health(int http_port) { return fetch_health("127.0.0.1", http_port); }

}  // namespace skinstream::server
