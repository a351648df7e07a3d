// The limit of unsent bytes on a real loopback TCP connection whose reader never reads: the
// socket takes about the limit, not the megabytes of its send buffer.
#include "server/tcp_unsent_limit.h"

#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cerrno>
#include <vector>

#include "server/asio.h"

namespace skinstream::server {
namespace {

// A connected pair on 127.0.0.1: the sending end non-blocking, the receiving end with a small
// receive buffer and never read.
struct UnreadLoopbackPair {
  asio::io_context io;
  tcp::socket receiver{io}, sender_socket{io};
  int sender = -1;
  UnreadLoopbackPair() {
    tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    receiver.open(tcp::v4());
    receiver.set_option(asio::socket_base::receive_buffer_size(4096));
    receiver.connect(acceptor.local_endpoint());
    acceptor.accept(sender_socket);
    sender_socket.non_blocking(true);
    sender = sender_socket.native_handle();
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
  const UnreadLoopbackPair unlimited;
  ASSERT_GE(unlimited.sender, 0);
  const size_t without = unlimited.bytes_taken();

  const UnreadLoopbackPair limited;
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
