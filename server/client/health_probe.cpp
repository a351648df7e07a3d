#include "server/client/health_probe.h"

#include <array>
#include <string>

#include "server/asio.h"

namespace skinstream::server {

nlohmann::json fetch_health(const std::string& host, int http_port) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect({asio::ip::make_address(host), static_cast<unsigned short>(http_port)});
  const std::string request = "GET /health HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n";
  asio::write(socket, asio::buffer(request));
  std::string response;
  boost::system::error_code ec;
  std::array<char, 4096> buffer;
  while (size_t n = socket.read_some(asio::buffer(buffer), ec)) response.append(buffer.data(), n);
  const size_t body = response.find("\r\n\r\n");
  return nlohmann::json::parse(body == std::string::npos ? "{}" : response.substr(body + 4));
}

}  // namespace skinstream::server
