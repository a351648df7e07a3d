#include "server/client/control_client.h"

#include <array>

#include "server/asio.h"

namespace skinstream::server {

ControlReply post_control(const std::string& host, int http_port, const std::string& path,
                          const std::string& token) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect({asio::ip::make_address(host), static_cast<unsigned short>(http_port)});
  const std::string request =
      "POST " + path + " HTTP/1.1\r\nHost: " + host + "\r\nAuthorization: Bearer " + token +
      "\r\nX-Skinstream-Operator: bench\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
  asio::write(socket, asio::buffer(request));
  std::string response;
  boost::system::error_code ec;
  std::array<char, 4096> buffer;
  while (size_t n = socket.read_some(asio::buffer(buffer), ec)) response.append(buffer.data(), n);
  ControlReply reply;
  if (response.rfind("HTTP/1.1 ", 0) == 0 && response.size() >= 12)
    reply.status = std::stoi(response.substr(9, 3));
  const size_t body = response.find("\r\n\r\n");
  reply.body =
      nlohmann::json::parse(body == std::string::npos ? "{}" : response.substr(body + 4), nullptr, false);
  return reply;
}

}  // namespace skinstream::server
