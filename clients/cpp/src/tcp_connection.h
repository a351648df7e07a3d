#pragma once
// A blocking TCP connection with timeouts, on POSIX sockets (no dependency a renderer would not
// have). Internal to the client library.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace skinstream::client {

class TcpConnection {
 public:
  // Resolves and connects (TCP_NODELAY on); throws Error naming host, port and the reason.
  TcpConnection(const std::string& host, uint16_t port, std::chrono::milliseconds timeout);
  ~TcpConnection();
  TcpConnection(const TcpConnection&) = delete;
  TcpConnection& operator=(const TcpConnection&) = delete;

  // All of `bytes`, or throws Error.
  void send_all(std::span<const unsigned char> bytes);
  // Waits up to `timeout` for bytes, then reads what is there into `into`: the count read, 0 on
  // timeout. Throws Error when the peer closed the connection or the read failed.
  size_t receive(std::span<unsigned char> into, std::chrono::milliseconds timeout);

 private:
  int fd_ = -1;
  std::string peer_;
};

}  // namespace skinstream::client
