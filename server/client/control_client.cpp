#include "server/client/control_client.h"

#include "server/client/health_probe.h"

namespace skinstream::server {

ControlReply post_control(const std::string& host, int http_port, const std::string& path,
                          const std::string& token) {
  const HttpReply http =
      http_exchange(host, http_port,
                    "POST " + path + " HTTP/1.1\r\nHost: " + host + "\r\nAuthorization: Bearer " + token +
                        "\r\nX-Skinstream-Operator: bench\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
  return {http.status, nlohmann::json::parse(http.body.empty() ? "{}" : http.body, nullptr, false)};
}

}  // namespace skinstream::server
