#pragma once
// A POST to a running skinstreamd's control API (docs/control-api.md), for the bench: its
// recording A/B starts and stops takes through the same door an operator uses.

#include <nlohmann/json.hpp>
#include <string>

namespace skinstream::server {

struct ControlReply {
  int status = 0;  // the HTTP status (0: no reply)
  nlohmann::json body;
};

// POST `path` with the Bearer `token` and no body. Throws boost::system::system_error when the
// daemon cannot be reached.
ControlReply post_control(const std::string& host, int http_port, const std::string& path,
                          const std::string& token);

}  // namespace skinstream::server
