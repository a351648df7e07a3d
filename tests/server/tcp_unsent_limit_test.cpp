// The limit of unsent bytes on a real loopback TCP connection whose reader never reads: the
// socket takes about the limit, not the megabytes of its send buffer.
#include "server/tcp_unsent_limit.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <vector>

namespace skinstream::server {
namespace {

// A connected pair on 127.0.0.1: the sending end non-blocking, the receiving end with a small
// receive buffer and never read.
struct LoopbackPair {
  int sender = -1, receiver = -1;
  LoopbackPair() {
    const int listener = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address;
    bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address);
    listen(listener, 1);
    getsockname(listener, reinterpret_cast<sockaddr*>(&address), &size);
    receiver = socket(AF_INET, SOCK_STREAM, 0);
    const int small = 4096;
    setsockopt(receiver, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    connect(receiver, reinterpret_cast<sockaddr*>(&address), sizeof address);
    sender = accept(listener, nullptr, nullptr);
    close(listener);
    fcntl(sender, F_SETFL, fcntl(sender, F_GETFL) | O_NONBLOCK);
  }
  ~LoopbackPair() {
    close(sender);
    close(receiver);
  }
  // What the sending end takes before it would block.
  size_t bytes_taken() const {
    const std::vector<unsigned char> chunk(64 * 1024, 7);
    size_t taken = 0;
    for (;;) {
      const ssize_t n = send(sender, chunk.data(), chunk.size(), MSG_NOSIGNAL);
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK ? taken : 0;
      taken += static_cast<size_t>(n);
      if (taken > 64u * 1024 * 1024) return taken;  // no limit at all: stop somewhere
    }
  }
};

TEST(TcpUnsentLimit, ASocketThatIsNotReadTakesAboutTheLimitNotItsSendBuffer) {
  const LoopbackPair unlimited;
  ASSERT_GE(unlimited.sender, 0);
  const size_t without = unlimited.bytes_taken();

  const LoopbackPair limited;
  ASSERT_GE(limited.sender, 0);
  ASSERT_EQ(set_tcp_unsent_limit(limited.sender, 128 * 1024), "");
  EXPECT_EQ(tcp_unsent_limit_of(limited.sender), 128 * 1024);
  const size_t with = limited.bytes_taken();
  std::printf("a socket whose reader never reads took %zu bytes, %zu with a limit of 128 kB\n", without, with);
  // The limit, the reader's small window and at most one more send's worth beyond the limit.
  EXPECT_LT(with, 512u * 1024);
  EXPECT_GT(without, 2 * with);
}

TEST(TcpUnsentLimit, WhatIsNoTcpSocketSaysWhy) {
  EXPECT_NE(set_tcp_unsent_limit(-1, 1024).find("TCP_NOTSENT_LOWAT 1024: "), std::string::npos);
  EXPECT_EQ(tcp_unsent_limit_of(-1), -1);
}

}  // namespace
}  // namespace skinstream::server
