#include "server/listener.h"

#include <spdlog/spdlog.h>

#include <stdexcept>

namespace skinstream::server {

Listener::Listener(asio::io_context& io, const std::string& address, int port, std::string name, Accept on_accept,
                   std::string tcp_congestion)
    : io_(io), acceptor_(io), name_(std::move(name)), on_accept_(std::move(on_accept)),
      congestion_(name_, std::move(tcp_congestion)) {
  boost::system::error_code ec;
  const auto ip = asio::ip::make_address(address, ec);
  if (ec) throw std::runtime_error(name_ + ": bad listen address \"" + address + "\"");
  const tcp::endpoint endpoint(ip, static_cast<unsigned short>(port));
  auto fail = [&](const char* step) {
    throw std::runtime_error(name_ + ": cannot " + step + " " + address + ":" + std::to_string(port) + ": " + ec.message());
  };
  acceptor_.open(endpoint.protocol(), ec);
  if (ec) fail("open");
  acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
  acceptor_.bind(endpoint, ec);
  if (ec) fail("listen on");
  acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) fail("listen on");
  port_ = acceptor_.local_endpoint().port();
}

void Listener::start() { accept_next(); }

void Listener::stop() {
  boost::system::error_code ec;
  acceptor_.close(ec);
}

void Listener::accept_next() {
  acceptor_.async_accept([this](const boost::system::error_code& ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (ec) {
      spdlog::warn("{}: accept failed: {}", name_, ec.message());
    } else {
      boost::system::error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      congestion_.apply(socket.native_handle());
      on_accept_(std::move(socket));
    }
    accept_next();
  });
}

}  // namespace skinstream::server
