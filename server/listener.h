#pragma once
// Accepts TCP connections on one port and hands each socket to a callback (io thread). Binding
// happens in the constructor, so a port in use fails at startup with a clear message. Accepted
// sockets get TCP_NODELAY, when one is named that TCP congestion control
// (server/tcp_congestion.h), and when one is given a limit of unsent bytes
// (server/tcp_unsent_limit.h); when either cannot be set, the listener says so (rate-limited) and
// goes on with the system's.
//
// Out of file descriptors (EMFILE, ENFILE; ENOBUFS, ENOMEM alike) the waiting connection stays
// in the kernel's queue and every accept would fail at once: the listener pauses instead, 10 ms
// doubling to 1 s, counts each failure, and logs the episode when it starts and when accepts
// succeed again (rate-limited), so neither the io thread nor the log is flooded.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "server/asio.h"
#include "server/logging.h"
#include "server/tcp_congestion.h"

namespace skinstream::server {

class DescriptorReserve;
class Metrics;

struct ListenerOptions {
  std::string tcp_congestion;         // set on every accepted socket; empty: the system's
  Metrics* metrics = nullptr;         // counts accepts that failed for lack of descriptors
  DescriptorReserve* reserve = nullptr;  // taken back before every accept
  bool accept_on_reserve = false;     // out of descriptors, spend the reserve on the waiting connection
  int unsent_limit_bytes = 0;         // set on every accepted socket (server/tcp_unsent_limit.h); 0: none
};

class Listener {
 public:
  using Accept = std::function<void(tcp::socket socket)>;
  static constexpr std::chrono::milliseconds kFirstPause{10}, kLongestPause{1000};

  // Throws std::runtime_error naming the address and port when it cannot listen.
  Listener(asio::io_context& io, const std::string& address, int port, std::string name, Accept on_accept,
           ListenerOptions options = {});
  void start();
  void stop();
  int port() const { return port_; }

 private:
  void accept_next(bool take_reserve_back = true);
  void on_accept_failed(const boost::system::error_code& ec);
  void end_exhaustion();

  tcp::acceptor acceptor_;
  asio::steady_timer pause_timer_;
  std::string name_;
  Accept on_accept_;
  ListenerOptions options_;
  AcceptedSocketCongestion congestion_;
  RateLimitedLog log_;
  int port_ = 0;
  // The current episode of failed accepts for lack of descriptors (none while failures == 0).
  std::chrono::milliseconds pause_ = kFirstPause;
  uint64_t episode_failures_ = 0;
  std::chrono::steady_clock::time_point episode_start_{};
};

}  // namespace skinstream::server
