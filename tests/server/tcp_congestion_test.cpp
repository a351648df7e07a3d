// The congestion control of real loopback sockets: set, read back, refused with a reason.
#include "server/tcp_congestion.h"

#include <gtest/gtest.h>

#include "server/asio.h"

namespace skinstream::server {
namespace {

struct LoopbackPair {
  asio::io_context io;
  tcp::acceptor acceptor{io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  tcp::socket client{io}, server{io};
  LoopbackPair() {
    client.connect(acceptor.local_endpoint());
    acceptor.accept(server);
  }
};

TEST(TcpCongestion, RenoIsSetAndReadBack) {
  LoopbackPair pair;
  const std::string before = tcp_congestion_of(pair.server.native_handle());
  EXPECT_EQ(before, system_tcp_congestion());  // what a new socket gets
  EXPECT_EQ(set_tcp_congestion(pair.server.native_handle(), "reno"), "");
  EXPECT_EQ(tcp_congestion_of(pair.server.native_handle()), "reno");
  // Still a working connection.
  const std::string hello = "hello";
  asio::write(pair.server, asio::buffer(hello));
  std::string received(hello.size(), '\0');
  asio::read(pair.client, asio::buffer(received));
  EXPECT_EQ(received, hello);
}

TEST(TcpCongestion, UnknownAlgorithmIsRefusedWithAReasonAndChangesNothing) {
  LoopbackPair pair;
  const std::string before = tcp_congestion_of(pair.server.native_handle());
  const std::string problem = set_tcp_congestion(pair.server.native_handle(), "no_such_cc");
  EXPECT_NE(problem, "");
  EXPECT_NE(problem.find("tcp_available_congestion_control"), std::string::npos) << problem;
  EXPECT_EQ(tcp_congestion_of(pair.server.native_handle()), before);
}

TEST(TcpCongestion, NotASocketReadsAsEmpty) {
  EXPECT_EQ(tcp_congestion_of(-1), "");
  EXPECT_NE(set_tcp_congestion(-1, "reno"), "");
}

TEST(TcpCongestion, NamesAreCheckedBeforeTheKernelSeesThem) {
  EXPECT_TRUE(is_tcp_congestion_name("reno"));
  EXPECT_TRUE(is_tcp_congestion_name("bbr"));
  EXPECT_TRUE(is_tcp_congestion_name("highspeed-2_x"));
  EXPECT_FALSE(is_tcp_congestion_name(""));
  EXPECT_FALSE(is_tcp_congestion_name("CUBIC"));
  EXPECT_FALSE(is_tcp_congestion_name("cubic;"));
  EXPECT_FALSE(is_tcp_congestion_name("sixteen_chars_xx"));
  EXPECT_TRUE(is_tcp_congestion_name("fifteen_chars_x"));
}

}  // namespace
}  // namespace skinstream::server
