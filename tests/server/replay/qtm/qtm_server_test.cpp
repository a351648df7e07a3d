// The QTM RT replay server as a client meets it over a real loopback socket: what a client
// wrote and the server quotes back in an Error packet stays one printable line.
#include "server/replay/qtm/qtm_server.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "support/replay_capture.h"
#include "support/source_sink_recorder.h"

namespace skinstream::server {
namespace {

// The server's packets to one connected client, read on the test's thread.
class QtmClient {
 public:
  QtmClient(asio::io_context& io, uint16_t port) : socket_(io) {
    socket_.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  }
  void command(const std::string& text) { asio::write(socket_, asio::buffer(qtm::encode_text(qtm::PacketType::Command, text))); }
  // The text of the next packet of `type` (others skipped).
  std::string next_text(qtm::PacketType type) {
    for (;;) {
      qtm::Bytes packet;
      while (framer_.next(packet) != qtm::PacketFramer::Status::Packet) {
        const std::span<unsigned char> room = framer_.prepare(4096);
        framer_.commit(socket_.read_some(asio::buffer(room.data(), room.size())));
      }
      uint32_t got = 0;
      std::string text, error;
      if (!qtm::read_header(packet, got, error)) return "bad packet: " + error;
      if (got == static_cast<uint32_t>(type) && qtm::decode_text(packet, text, error)) return text;
    }
  }

 private:
  tcp::socket socket_;
  qtm::PacketFramer framer_;
};

bool one_printable_line(const std::string& text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
}

// A UDP address with a bell and a terminal escape in it (a hostile or broken client):
// refused with an Error whose text shows those bytes escaped.
TEST(QtmServer, ABadUdpAddressIsQuotedEscapedInTheError) {
  const Capture walker = test::replay_capture(60, 0.0);
  test::IoThread server_io;
  QtmServerOptions options;
  options.bind_address = "127.0.0.1";
  options.port = 0;
  QtmServer server(server_io.io, {{"walker", &walker}}, options);
  server_io.call([&] { server.start(); });
  asio::io_context client_io;
  QtmClient client(client_io, server_io.call([&] { return server.port(); }));
  EXPECT_EQ(client.next_text(qtm::PacketType::Command), "QTM RT Interface connected");
  client.command("StreamFrames AllFrames UDP:\x1b[2Jno\x07host:5000 3D");
  const std::string error = client.next_text(qtm::PacketType::Error);
  EXPECT_NE(error.find("bad UDP address"), std::string::npos) << error;
  EXPECT_NE(error.find("\\x1b[2Jno\\x07host"), std::string::npos) << error;
  EXPECT_TRUE(one_printable_line(error)) << error;
  EXPECT_EQ(server.stats().commands_refused.load(), 1u);
  server_io.call([&] { server.stop(); });
}

}  // namespace
}  // namespace skinstream::server
