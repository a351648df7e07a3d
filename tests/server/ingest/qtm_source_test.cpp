// The daemon's QtmSource against the QTM RT replay server (server/replay/qtm/qtm_server) over real
// loopback sockets: subjects from the label prefixes, exact positions, occlusion, unlabelled
// points, TCP and UDP streaming, a server that vanishes and comes back, and scripted servers that
// send malformed, truncated, inconsistent and non-finite input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <thread>

#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "protocol/qtm/qtm_parameters.h"
#include "server/ingest/qtm_source.h"
#include "server/replay/qtm/qtm_server.h"
#include "support/replay_capture.h"
#include "support/silent_capture_servers.h"
#include "support/source_sink_recorder.h"

namespace skinstream::server {
namespace {

using namespace std::chrono_literals;
using test::IoThread;
using test::SourceSinkRecorder;

QtmServerOptions fast_server(uint16_t port = 0) {
  QtmServerOptions o;
  o.bind_address = "127.0.0.1";
  o.port = port;
  o.speed = 4.0;
  o.loop = true;
  return o;
}

QtmSourceOptions qtm_client_of(uint16_t port) {
  QtmSourceOptions o;
  o.port = port;
  o.initial_backoff_seconds = 0.05;
  o.max_backoff_seconds = 0.2;
  return o;
}

void expect_near(const Vec3& got, const Vec3& want) {
  // float32 on the wire: within 1e-7 relative of a coordinate below 10 m.
  EXPECT_LT((got - want).norm(), 1e-3) << got.transpose() << " vs " << want.transpose();
}

TEST(QtmSource, StreamsSeveralSubjectsAsRecorded) {
  const Capture walker = test::replay_capture(60, 0.0), runner = test::replay_capture(60, 500.0);
  IoThread server_io, client_io;
  QtmServer server(server_io.io, {{"walker", &walker}, {"runner_2", &runner}}, fast_server());
  server_io.call([&] { server.start(); });
  SourceSinkRecorder sink;
  QtmSource source(client_io.io, qtm_client_of(server_io.call([&] { return server.port(); })), sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(30));
  source.stop();
  client_io.call([] {});
  server_io.call([&] { server.stop(); });  // on its own thread, before it is destroyed

  std::lock_guard lock(sink.mutex);
  ASSERT_TRUE(sink.count_state(SourceState::Streaming) == 1);
  const SourceFrame& first = sink.frames.front();
  ASSERT_EQ(first.subjects.size(), 2u);
  EXPECT_EQ(first.subjects[0].name, "walker");
  EXPECT_EQ(first.subjects[1].name, "runner-2");  // QTM prefixes hold no '_'
  EXPECT_EQ(first.subjects[1].labels, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(first.structure_version, 1u);
  EXPECT_DOUBLE_EQ(first.rate_hz, 120.0);
  for (const SourceFrame& f : sink.frames) {
    const int index = static_cast<int>(f.frame_number - 100) % 60;
    ASSERT_GE(index, 0);
    EXPECT_EQ(f.source_time_ns, std::llround((f.frame_number - 100) * 1e6 / 120.0) * 1000);
    for (size_t s = 0; s < 2; ++s) {
      const Capture& c = s == 0 ? walker : runner;
      for (int m = 0; m < 2; ++m) {
        if (c.present(index, m))
          expect_near(f.labelled[s][static_cast<size_t>(m)], c.at(index, m));
        else
          EXPECT_FALSE(is_present(f.labelled[s][static_cast<size_t>(m)])) << "frame " << f.frame_number;
      }
    }
    ASSERT_EQ(f.unlabelled.size(), 2u);
    EXPECT_EQ(f.unlabelled_ids[0], 3);
    EXPECT_EQ(f.unlabelled_ids[1], 3 + 1'000'000);
    expect_near(f.unlabelled[1], runner.at(index, 2));
  }
}

TEST(QtmSource, StreamsOverUdp) {
  const Capture walker = test::replay_capture(60, 0.0);
  IoThread server_io, client_io;
  QtmServer server(server_io.io, {{"walker", &walker}}, fast_server());
  server_io.call([&] { server.start(); });
  uint16_t free_port = 0;
  {
    udp::socket probe(client_io.io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    free_port = probe.local_endpoint().port();
  }
  QtmSourceOptions options = qtm_client_of(server_io.call([&] { return server.port(); }));
  options.udp_port = free_port;
  SourceSinkRecorder sink;
  QtmSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(10));
  source.stop();
  client_io.call([] {});  // no handler of the source runs after this: the sink may go
  server_io.call([&] { server.stop(); });  // on its own thread, before it is destroyed
  // The 10 frames came as datagrams: none left over TCP. (The sent-datagram count is taken in
  // completion handlers, which may lag the receiver by one; it only has to be positive.)
  EXPECT_EQ(server.stats().frame_packets_sent.load(), 0u);
  EXPECT_GT(server.stats().datagrams_sent.load(), 0u);
}

TEST(QtmSource, AServerThatVanishesIsReportedAndFoundAgain) {
  const Capture walker = test::replay_capture(60, 0.0);
  IoThread server_io, client_io;
  auto server = std::make_unique<QtmServer>(server_io.io, std::vector<ReplaySubject>{{"walker", &walker}}, fast_server());
  server_io.call([&] { server->start(); });
  const uint16_t port = server_io.call([&] { return server->port(); });
  SourceSinkRecorder sink;
  QtmSource source(client_io.io, qtm_client_of(port), sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(5));
  server_io.call([&] { server.reset(); });  // gone: connection closed, port closed
  ASSERT_TRUE(sink.wait_state(SourceState::Disconnected));
  const size_t before = sink.with_frames();
  server_io.call([&] {
    server = std::make_unique<QtmServer>(server_io.io, std::vector<ReplaySubject>{{"walker", &walker}}, fast_server(port));
    server->start();
  });
  ASSERT_TRUE(sink.wait_state(SourceState::Streaming, 2));
  ASSERT_TRUE(sink.wait_frames(before + 5));
  source.stop();
  client_io.call([] {});
  server_io.call([&] { server.reset(); });
}

// A QTM RT server played from a script on its own thread, for input a real server never sends.
class QtmScriptedServer {
 public:
  using Script = std::function<void(tcp::socket&, qtm::PacketFramer&)>;
  explicit QtmScriptedServer(Script script)
      : acceptor_(io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)), thread_([this, script] {
          for (;;) {
            tcp::socket socket(io_);
            boost::system::error_code ec;
            acceptor_.accept(socket, ec);
            if (ec || done_) return;
            ++connections;
            qtm::PacketFramer framer;
            try {
              script(socket, framer);
            } catch (const std::exception&) {  // the client went away
            }
          }
        }) {}
  ~QtmScriptedServer() {
    done_ = true;
    boost::system::error_code ec;
    tcp::socket poke(io_);
    poke.connect(acceptor_.local_endpoint(), ec);  // wakes accept()
    thread_.join();
  }
  uint16_t port() const { return acceptor_.local_endpoint().port(); }
  std::atomic<int> connections{0};

  // Blocking helpers for scripts.
  static void send(tcp::socket& s, const std::vector<unsigned char>& bytes) { asio::write(s, asio::buffer(bytes)); }
  static std::string next_command(tcp::socket& s, qtm::PacketFramer& framer) {
    for (;;) {
      qtm::Bytes packet;
      if (framer.next(packet) == qtm::PacketFramer::Status::Packet) {
        std::string text, error;
        qtm::decode_text(packet, text, error);
        return text;
      }
      const auto room = framer.prepare(4096);
      framer.commit(s.read_some(asio::buffer(room.data(), room.size())));
    }
  }
  // Welcome, version and parameters answered as QTM does; returns after StreamFrames.
  static void handshake(tcp::socket& s, qtm::PacketFramer& framer, const std::vector<std::string>& labels) {
    send(s, qtm::encode_text(qtm::PacketType::Command, qtm::kWelcome));
    next_command(s, framer);
    send(s, qtm::encode_text(qtm::PacketType::Command, "Version set to 1.19"));
    next_command(s, framer);
    qtm::Parameters p;
    p.frequency_hz = 100;
    p.has_3d = true;
    p.labels = labels;
    send(s, qtm::encode_text(qtm::PacketType::Xml, qtm::write_parameters_xml(p, 19)));
    next_command(s, framer);
  }
  static std::vector<unsigned char> frame(uint32_t number, std::vector<std::array<float, 3>> positions) {
    qtm::DataPacketWriter writer;
    writer.begin(number * 10000, number);
    writer.add_labelled(positions);
    const auto bytes = writer.finish();
    return {bytes.begin(), bytes.end()};
  }

 private:
  asio::io_context io_;
  tcp::acceptor acceptor_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

TEST(QtmSource, MalformedPacketIsCountedAndTheConnectionRetried) {
  QtmScriptedServer server([](tcp::socket& s, qtm::PacketFramer& framer) {
    QtmScriptedServer::handshake(s, framer, {"P_A"});
    QtmScriptedServer::send(s, QtmScriptedServer::frame(1, {{1, 2, 3}}));
    QtmScriptedServer::send(s, {4, 0, 0, 0, 3, 0, 0, 0});  // a size below the header: unrecoverable
    std::this_thread::sleep_for(200ms);
  });
  IoThread client_io;
  SourceSinkRecorder sink;
  QtmSource source(client_io.io, qtm_client_of(server.port()), sink);
  source.start();
  ASSERT_TRUE(sink.wait_bad_input("malformed_packet"));
  ASSERT_TRUE(sink.wait_state(SourceState::Disconnected));
  ASSERT_TRUE(test::eventually([&] { return server.connections >= 2; }));  // it came back
  source.stop();
  client_io.call([] {});
  EXPECT_NE(sink.last_detail(SourceState::Disconnected).find("malformed packet"), std::string::npos);
  EXPECT_GE(sink.frames.size(), 1u);  // the good frame before the bad packet was handed on
}

TEST(QtmSource, TruncatedStreamAndRefusedHandshakeDisconnect) {
  QtmScriptedServer truncated([](tcp::socket& s, qtm::PacketFramer& framer) {
    QtmScriptedServer::handshake(s, framer, {"P_A"});
    auto f = QtmScriptedServer::frame(1, {{1, 2, 3}});
    f.resize(f.size() / 2);  // half a packet, then the server closes
    QtmScriptedServer::send(s, f);
  });
  QtmScriptedServer refusing([](tcp::socket& s, qtm::PacketFramer& framer) {
    QtmScriptedServer::send(s, qtm::encode_text(qtm::PacketType::Command, qtm::kWelcome));
    QtmScriptedServer::next_command(s, framer);
    QtmScriptedServer::send(s, qtm::encode_text(qtm::PacketType::Error, "Version NOT supported"));
    std::this_thread::sleep_for(200ms);
  });
  IoThread client_io;
  SourceSinkRecorder a, b;
  QtmSource to_truncated(client_io.io, qtm_client_of(truncated.port()), a);
  QtmSource to_refusing(client_io.io, qtm_client_of(refusing.port()), b);
  to_truncated.start();
  to_refusing.start();
  ASSERT_TRUE(a.wait_state(SourceState::Disconnected));
  ASSERT_TRUE(b.wait_state(SourceState::Disconnected));
  to_truncated.stop();
  to_refusing.stop();
  client_io.call([] {});
  EXPECT_NE(a.last_detail(SourceState::Disconnected).find("closed the connection"), std::string::npos);
  EXPECT_TRUE(a.frames.empty());
  EXPECT_NE(b.last_detail(SourceState::Disconnected).find("Version NOT supported"), std::string::npos);
}

TEST(QtmSource, WrongMarkerCountAsksForTheLabelsAgainAndInfinityIsMissing) {
  std::atomic<int> parameter_requests{0};
  QtmScriptedServer server([&](tcp::socket& s, qtm::PacketFramer& framer) {
    QtmScriptedServer::handshake(s, framer, {"P_A", "P_B"});
    ++parameter_requests;
    QtmScriptedServer::send(s, QtmScriptedServer::frame(1, {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}}));  // 3 markers, 2 labels
    if (QtmScriptedServer::next_command(s, framer).rfind("GetParameters", 0) == 0) ++parameter_requests;
    const float inf = std::numeric_limits<float>::infinity();
    QtmScriptedServer::send(s, QtmScriptedServer::frame(2, {{inf, 2, 3}, {4, 5, 6}}));
    std::this_thread::sleep_for(500ms);
  });
  IoThread client_io;
  SourceSinkRecorder sink;
  QtmSource source(client_io.io, qtm_client_of(server.port()), sink);
  source.start();
  ASSERT_TRUE(sink.wait_bad_input("label_count_mismatch"));
  ASSERT_TRUE(sink.wait_bad_input("non_finite_point"));
  ASSERT_TRUE(sink.wait_frames(1));
  source.stop();
  client_io.call([] {});
  EXPECT_EQ(parameter_requests.load(), 2);
  ASSERT_EQ(sink.frames.size(), 1u);  // frame 1 was dropped, frame 2 handed on
  EXPECT_EQ(sink.frames[0].frame_number, 2u);
  EXPECT_FALSE(is_present(sink.frames[0].labelled[0][0]));
  EXPECT_EQ(sink.frames[0].labelled[0][1], Vec3(4, 5, 6));
}

// A server that accepts and never answers kept the source "connecting" for ever: it is left
// after the handshake timeout, reported and tried again.
TEST(QtmSource, ASilentServerIsLeftAfterTheHandshakeTimeoutAndTriedAgain) {
  test::SilentQtmServer silent({.handshake = false});
  IoThread client_io;
  SourceSinkRecorder sink;
  QtmSourceOptions options = qtm_client_of(silent.port());
  options.handshake_timeout = 300ms;
  QtmSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_state(SourceState::Disconnected));
  ASSERT_TRUE(test::eventually([&] { return silent.connections() >= 2; }));
  source.stop();
  client_io.call([] {});
  EXPECT_NE(sink.last_detail(SourceState::Disconnected).find("within 300 ms (waiting for the welcome)"), std::string::npos)
      << sink.last_detail(SourceState::Disconnected);
  EXPECT_TRUE(sink.frames.empty());
}

// One that stops sending with its connection open was shown streaming while the frames stayed
// frozen: it is reported stalled and tried again.
TEST(QtmSource, AServerThatGoesSilentIsStalledAndTriedAgain) {
  test::SilentQtmServer silent({.frames = 5});
  IoThread client_io;
  SourceSinkRecorder sink;
  QtmSourceOptions options = qtm_client_of(silent.port());
  options.stall_timeout = 300ms;
  QtmSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(5));
  ASSERT_TRUE(sink.wait_state(SourceState::Stalled));
  ASSERT_TRUE(test::eventually([&] { return silent.connections() >= 2; }));
  source.stop();
  client_io.call([] {});
  EXPECT_NE(sink.last_detail(SourceState::Stalled).find("stalled: no frame from 127.0.0.1:"), std::string::npos)
      << sink.last_detail(SourceState::Stalled);
  EXPECT_EQ(sink.count_state(SourceState::Disconnected), 0u);
}

// Silence after NoMoreData is a measurement that ended, not a stall: nothing is retried.
TEST(QtmSource, SilenceAfterTheMeasurementEndedIsNoStall) {
  QtmScriptedServer server([](tcp::socket& s, qtm::PacketFramer& framer) {
    QtmScriptedServer::handshake(s, framer, {"P_A"});
    QtmScriptedServer::send(s, QtmScriptedServer::frame(1, {{1, 2, 3}}));
    QtmScriptedServer::send(s, qtm::encode_no_more_data());
    std::this_thread::sleep_for(1500ms);
  });
  IoThread client_io;
  SourceSinkRecorder sink;
  QtmSourceOptions options = qtm_client_of(server.port());
  options.stall_timeout = 300ms;
  QtmSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_state(SourceState::Finished));
  std::this_thread::sleep_for(1000ms);  // more than three stall times of silence
  source.stop();
  client_io.call([] {});
  EXPECT_EQ(sink.count_state(SourceState::Stalled), 0u);
  EXPECT_EQ(sink.count_state(SourceState::Disconnected), 0u);
  EXPECT_EQ(server.connections.load(), 1);
}

TEST(QtmServer, RefusesWhatItCannotDoAndClosesOnGarbage) {
  const Capture walker = test::replay_capture(10, 0.0);
  IoThread server_io;
  QtmServer server(server_io.io, {{"walker", &walker}}, fast_server());
  server_io.call([&] { server.start(); });
  asio::io_context io;
  tcp::socket s(io);
  s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server_io.call([&] { return server.port(); })));
  qtm::PacketFramer framer;
  auto next = [&](uint32_t& type) {
    for (;;) {
      qtm::Bytes packet;
      if (framer.next(packet) == qtm::PacketFramer::Status::Packet) {
        std::string text, error;
        qtm::read_header(packet, type, error);
        qtm::decode_text(packet, text, error);
        return text;
      }
      const auto room = framer.prepare(4096);
      framer.commit(s.read_some(asio::buffer(room.data(), room.size())));
    }
  };
  uint32_t type = 0;
  EXPECT_EQ(next(type), qtm::kWelcome);
  QtmScriptedServer::send(s, qtm::encode_text(qtm::PacketType::Command, "Version 1.5"));
  EXPECT_EQ(next(type), "Version NOT supported");
  EXPECT_EQ(type, static_cast<uint32_t>(qtm::PacketType::Error));
  QtmScriptedServer::send(s, qtm::encode_text(qtm::PacketType::Command, "TakeControl"));
  EXPECT_NE(next(type).find("not supported"), std::string::npos);
  QtmScriptedServer::send(s, qtm::encode_text(qtm::PacketType::Command, "StreamFrames AllFrames 6D"));
  EXPECT_NE(next(type).find("3D"), std::string::npos);
  QtmScriptedServer::send(s, {0xFF, 0xFF, 0xFF, 0xFF, 1, 0, 0, 0});  // a 4 GB packet: closed
  boost::system::error_code ec;
  char byte;
  s.read_some(asio::buffer(&byte, 1), ec);
  EXPECT_EQ(ec, asio::error::eof);
  EXPECT_EQ(server.stats().bad_clients.load(), 1u);
  EXPECT_EQ(server.stats().commands_refused.load(), 3u);
  server_io.call([&] { server.stop(); });
}

}  // namespace
}  // namespace skinstream::server
