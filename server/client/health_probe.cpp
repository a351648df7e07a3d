#include "server/client/health_probe.h"

#include <array>
#include <string>

#include "server/asio.h"

namespace skinstream::server {

HttpReply http_exchange(const std::string& host, int http_port, const std::string& request) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect({asio::ip::make_address(host), static_cast<unsigned short>(http_port)});
  asio::write(socket, asio::buffer(request));
  std::string response;
  boost::system::error_code ec;
  std::array<char, 4096> buffer;
  while (size_t n = socket.read_some(asio::buffer(buffer), ec)) response.append(buffer.data(), n);
  HttpReply reply;
  if (response.rfind("HTTP/1.1 ", 0) == 0 && response.size() >= 12)
    reply.status = std::stoi(response.substr(9, 3));
  const size_t body = response.find("\r\n\r\n");
  if (body != std::string::npos) reply.body = response.substr(body + 4);
  return reply;
}

nlohmann::json fetch_health(const std::string& host, int http_port) {
  const HttpReply reply = http_exchange(
      host, http_port, "GET /health HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n");
  return nlohmann::json::parse(reply.body.empty() ? "{}" : reply.body);
}

}  // namespace skinstream::server
