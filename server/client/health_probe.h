#pragma once
// GET /health from a running skinstreamd on this machine, for the bench and the end-to-end tests.
#include <nlohmann/json.hpp>

namespace skinstream::server {

// The daemon's /health JSON from 127.0.0.1:http_port ({} when the reply has no body). Throws
// boost::system::system_error when the daemon cannot be reached, nlohmann::json::exception for a
// body that is not JSON.
nlohmann::json fetch_health(int http_port);

}  // namespace skinstream::server
