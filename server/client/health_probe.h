#pragma once
// GET /health from a running skinstreamd, for the bench and the end-to-end tests.
#include <nlohmann/json.hpp>
#include <string>

namespace skinstream::server {

// The daemon's /health JSON from host:http_port ({} when the reply has no body). Throws
// boost::system::system_error when the daemon cannot be reached, nlohmann::json::exception for a
// body that is not JSON.
nlohmann::json fetch_health(const std::string& host, int http_port);
inline nlohmann::json fetch_health(int http_port) { return fetch_health("127.0.0.1", http_port); }

}  // namespace skinstream::server
