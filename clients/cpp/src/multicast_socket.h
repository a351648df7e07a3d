#pragma once
// A UDP socket that joins an IPv4 multicast group on a named interface, with a timed receive, on
// POSIX sockets. Internal to the client library.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace skinstream::client {

class MulticastSocket {
 public:
  // Binds group:port (several receivers on one host may) and joins the group on the interface
  // with that address (0.0.0.0: the system's choice); throws Error naming what failed.
  MulticastSocket(const std::string& group, uint16_t port, const std::string& interface_address);
  ~MulticastSocket();
  MulticastSocket(const MulticastSocket&) = delete;
  MulticastSocket& operator=(const MulticastSocket&) = delete;

  // Waits up to `timeout` for a datagram and reads it into `into`: its size (cut to `into`'s
  // size when longer, which the protocol then rejects), 0 on timeout. `out_arrival` is when the
  // kernel received it (on the steady clock), not when it was read: a reader busy with the last
  // frame must not think the next one's datagrams came late. Throws Error when the read fails.
  size_t receive(std::span<unsigned char> into, std::chrono::milliseconds timeout, std::chrono::steady_clock::time_point& out_arrival);

 private:
  int fd_ = -1;
  std::string where_;
};

}  // namespace skinstream::client
