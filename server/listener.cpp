#include "server/listener.h"

#include <spdlog/fmt/fmt.h>

#include <cerrno>
#include <stdexcept>

#include "server/descriptor_reserve.h"
#include "server/metrics/metrics.h"
#include "server/tcp_unsent_limit.h"

namespace skinstream::server {
namespace {

// Errors that say the process or the system has no descriptor or buffer for a new socket: the
// next accept fails the same way until something closes.
bool out_of_descriptors(const boost::system::error_code& ec) {
  if (ec.category() != boost::system::system_category()) return false;
  const int e = ec.value();
  return e == EMFILE || e == ENFILE || e == ENOBUFS || e == ENOMEM;
}

}  // namespace

Listener::Listener(asio::io_context& io, const std::string& address, int port, std::string name, Accept on_accept,
                   ListenerOptions options)
    : acceptor_(io), pause_timer_(io), name_(std::move(name)), on_accept_(std::move(on_accept)), options_(std::move(options)),
      congestion_(name_, options_.tcp_congestion) {
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
  pause_timer_.cancel();
  acceptor_.close(ec);
}

void Listener::accept_next(bool take_reserve_back) {
  if (take_reserve_back && options_.reserve) options_.reserve->restore();
  acceptor_.async_accept([this](const boost::system::error_code& ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (ec) return on_accept_failed(ec);
    end_exhaustion();
    boost::system::error_code ignored;
    socket.set_option(tcp::no_delay(true), ignored);
    congestion_.apply(socket.native_handle());
    if (options_.unsent_limit_bytes > 0)
      if (const std::string why = set_tcp_unsent_limit(socket.native_handle(), options_.unsent_limit_bytes); !why.empty())
        log_.warn(name_ + " unsent limit", "cannot limit an accepted socket's unsent bytes: " + why);
    on_accept_(std::move(socket));
    accept_next();
  });
}

void Listener::on_accept_failed(const boost::system::error_code& ec) {
  if (!out_of_descriptors(ec)) {  // one connection's trouble (e.g. reset before it was taken): go on
    log_.warn(name_, "accept failed: " + ec.message());
    return accept_next();
  }
  if (options_.metrics) options_.metrics->accepts_failed_no_descriptor.fetch_add(1, std::memory_order_relaxed);
  const bool first = episode_failures_++ == 0;
  if (first) episode_start_ = std::chrono::steady_clock::now();
  // Into the slot the reserve frees (taken back by a later accept, once a slot is free again).
  if (options_.accept_on_reserve && options_.reserve && options_.reserve->release()) {
    if (first) log_.warn(name_, "accept failed: " + ec.message() + ": taking this connection on the reserved descriptor");
    return accept_next(false);
  }
  if (first)
    log_.warn(name_, fmt::format("accept failed: {}: pausing accepts ({} ms, doubling to {} ms) until a descriptor is free",
                                 ec.message(), kFirstPause.count(), kLongestPause.count()));
  pause_timer_.expires_after(pause_);
  pause_ = std::min(pause_ * 2, kLongestPause);
  pause_timer_.async_wait([this](const boost::system::error_code& timer_ec) {
    if (!timer_ec && acceptor_.is_open()) accept_next();
  });
}

void Listener::end_exhaustion() {
  if (episode_failures_ == 0) return;
  using Seconds = std::chrono::duration<double>;
  log_.warn(name_, fmt::format("accepting again after {} accepts failed for lack of descriptors over {:.1f} s", episode_failures_,
                               Seconds(std::chrono::steady_clock::now() - episode_start_).count()));
  episode_failures_ = 0;
  pause_ = kFirstPause;
}

}  // namespace skinstream::server
