#pragma once
// Accepts TCP connections on one port and hands each socket to a callback (io thread). Binding
// happens in the constructor, so a port in use fails at startup with a clear message. Accepted
// sockets get TCP_NODELAY and, when one is named, that TCP congestion control
// (server/tcp_congestion.h); when it cannot be set, the listener says so once and goes on with
// the system's.

#include <functional>
#include <string>

#include "server/asio.h"
#include "server/tcp_congestion.h"

namespace skinstream::server {

class Listener {
 public:
  using Accept = std::function<void(tcp::socket socket)>;
  // Throws std::runtime_error naming the address and port when it cannot listen.
  Listener(asio::io_context& io, const std::string& address, int port, std::string name, Accept on_accept,
           std::string tcp_congestion = {});
  void start();
  void stop();
  int port() const { return port_; }

 private:
  void accept_next();
  asio::io_context& io_;
  tcp::acceptor acceptor_;
  std::string name_;
  Accept on_accept_;
  AcceptedSocketCongestion congestion_;
  int port_ = 0;
};

}  // namespace skinstream::server
