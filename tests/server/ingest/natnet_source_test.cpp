// The daemon's NatNetSource against the NatNet replay server (server/replay/natnet/natnet_server) over
// real loopback sockets: marker sets as subjects in millimetres, occlusion, unlabelled points,
// the 3.1 and 4.1 layouts, unicast and multicast, a server that vanishes and comes back, and a
// scripted server that sends malformed, truncated and unknown input.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <sys/socket.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <thread>

#include "protocol/natnet/natnet_capture_encoder.h"
#include "protocol/natnet/natnet_reader.h"
#include "protocol/natnet/natnet_writer.h"
#include "server/ingest/natnet_source.h"
#include "server/replay/natnet/natnet_server.h"
#include "support/replay_capture.h"
#include "support/silent_capture_servers.h"
#include "support/source_sink_recorder.h"

namespace skinstream::server {
namespace {

using namespace std::chrono_literals;
using test::IoThread;
using test::SourceSinkRecorder;

NatNetServerOptions unicast_server(natnet::Version version, uint16_t port = 0) {
  NatNetServerOptions o;
  o.bind_address = "127.0.0.1";
  o.command_port = port;
  o.multicast = false;
  o.version = version;
  o.speed = 4.0;
  o.loop = true;
  return o;
}

NatNetSourceOptions natnet_client_of(uint16_t port) {
  NatNetSourceOptions o;
  o.command_port = port;
  o.initial_backoff_seconds = 0.05;
  o.max_backoff_seconds = 0.2;
  o.reply_timeout = 300ms;
  o.stall_timeout = 300ms;
  o.keep_alive_interval = 100ms;
  return o;
}

uint16_t free_udp_port() {
  asio::io_context io;
  udp::socket probe(io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  return probe.local_endpoint().port();
}

void expect_frames_match(SourceSinkRecorder& sink, const Capture& walker, const Capture& runner) {
  std::lock_guard lock(sink.mutex);
  const SourceFrame& first = sink.frames.front();
  ASSERT_EQ(first.subjects.size(), 2u);
  EXPECT_EQ(first.subjects[0].name, "walker");
  EXPECT_EQ(first.subjects[1].name, "runner_2");
  EXPECT_EQ(first.subjects[0].labels, (std::vector<std::string>{"A", "B"}));
  for (const SourceFrame& f : sink.frames) {
    const int index = static_cast<int>(f.frame_number - 100) % 60;
    EXPECT_NEAR(f.source_time_ns * 1e-9, (f.frame_number - 100) / 120.0, 1e-6);
    for (size_t s = 0; s < 2; ++s) {
      const Capture& c = s == 0 ? walker : runner;
      for (int m = 0; m < 2; ++m) {
        const Vec3& got = f.labelled[s][static_cast<size_t>(m)];
        if (c.present(index, m))  // float32 metres: within 1e-7 relative
          EXPECT_LT((got - c.at(index, m)).norm(), 1e-3) << got.transpose() << " frame " << f.frame_number;
        else
          EXPECT_FALSE(is_present(got)) << "frame " << f.frame_number;
      }
    }
    ASSERT_EQ(f.unlabelled.size(), 2u);
    EXPECT_EQ(f.unlabelled_ids[0], 3);
    EXPECT_EQ(f.unlabelled_ids[1], 3 + 10'000);
    EXPECT_LT((f.unlabelled[1] - runner.at(index, 2)).norm(), 1e-3);
    EXPECT_TRUE(f.timecode.valid);
  }
  EXPECT_NEAR(sink.frames.back().rate_hz, 120.0, 0.01);
}

class NatNetLayouts : public ::testing::TestWithParam<natnet::Version> {};

TEST_P(NatNetLayouts, UnicastStreamsMarkerSetsInMillimetres) {
  const Capture walker = test::replay_capture(60, 0.0), runner = test::replay_capture(60, 500.0);
  IoThread server_io, client_io;
  NatNetServer server(server_io.io, {{"walker", &walker}, {"runner_2", &runner}}, unicast_server(GetParam()));
  server_io.call([&] { server.start(); });
  SourceSinkRecorder sink;
  NatNetSource source(client_io.io, natnet_client_of(server_io.call([&] { return server.command_port(); })), sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(70));  // more than half a second of the source's clock: its rate known
  source.stop();
  client_io.call([] {});
  server_io.call([&] { server.stop(); });  // on its own thread, before it is destroyed
  expect_frames_match(sink, walker, runner);
  EXPECT_EQ(server.stats().clients_connected.load(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Versions, NatNetLayouts,
                         ::testing::Values(natnet::Version{3, 1}, natnet::Version{4, 0}, natnet::Version{4, 1}),
                         [](const auto& info) {
                           return "NatNet" + std::to_string(info.param.major) + std::to_string(info.param.minor);
                         });

TEST(NatNetSource, Multicast) {
  const Capture walker = test::replay_capture(60, 0.0), runner = test::replay_capture(60, 500.0);
  IoThread server_io, client_io;
  NatNetServerOptions options = unicast_server({4, 1});
  options.multicast = true;
  options.multicast_group = "239.255.42.98";
  options.multicast_interface = "127.0.0.1";
  options.data_port = free_udp_port();
  NatNetServer server(server_io.io, {{"walker", &walker}, {"runner_2", &runner}}, options);
  server_io.call([&] { server.start(); });
  NatNetSourceOptions client = natnet_client_of(server_io.call([&] { return server.command_port(); }));
  client.interface_address = "127.0.0.1";
  SourceSinkRecorder sink;
  NatNetSource source(client_io.io, client, sink);
  source.start();
  const bool got = sink.wait([&] { return sink.frames.size() >= 70 || !sink.bad_inputs.empty() ||
                                          sink.count_state(SourceState::Disconnected) > 0; });
  source.stop();
  client_io.call([] {});
  server_io.call([&] { server.stop(); });  // on its own thread, before it is destroyed
  if (!got || sink.frames.size() < 70)
    GTEST_SKIP() << "multicast is not looped back here: " << sink.last_detail(SourceState::Disconnected);
  expect_frames_match(sink, walker, runner);
  EXPECT_EQ(server.stats().clients_connected.load(), 0u);  // multicast keeps no client list
}

TEST(NatNetSource, AServerThatVanishesIsReportedAndFoundAgain) {
  const Capture walker = test::replay_capture(60, 0.0);
  IoThread server_io, client_io;
  auto server = std::make_unique<NatNetServer>(server_io.io, std::vector<ReplaySubject>{{"walker", &walker}},
                                               unicast_server({4, 1}));
  server_io.call([&] { server->start(); });
  const uint16_t port = server_io.call([&] { return server->command_port(); });
  SourceSinkRecorder sink;
  NatNetSource source(client_io.io, natnet_client_of(port), sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(5));
  server_io.call([&] { server.reset(); });  // silent: UDP says nothing when a server goes
  ASSERT_TRUE(sink.wait_state(SourceState::Stalled));
  EXPECT_NE(sink.last_detail(SourceState::Stalled).find("stalled: no frame from"), std::string::npos);
  const size_t before = sink.with_frames();
  server_io.call([&] {
    server = std::make_unique<NatNetServer>(server_io.io, std::vector<ReplaySubject>{{"walker", &walker}},
                                            unicast_server({4, 1}, port));
    server->start();
  });
  ASSERT_TRUE(sink.wait_state(SourceState::Streaming, 2));
  ASSERT_TRUE(sink.wait_frames(before + 5));
  source.stop();
  client_io.call([] {});
  server_io.call([&] { server.reset(); });
}

// A NatNet command port answering from a script, for input a real server never sends.
class NatNetScriptedServer {
 public:
  using Script = std::function<void(udp::socket&, const udp::endpoint& client, uint16_t request)>;
  explicit NatNetScriptedServer(Script script)
      : socket_(io_, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0)), thread_([this, script] {
          std::vector<unsigned char> buffer(natnet::kMaxMessageBytes);
          for (;;) {
            udp::endpoint client;
            boost::system::error_code ec;
            const size_t n = socket_.receive_from(asio::buffer(buffer), client, 0, ec);
            if (ec || done_) return;
            if (n < 4) continue;
            const uint16_t request = static_cast<uint16_t>(buffer[0] | buffer[1] << 8);
            ++requests[request < 16 ? request : 15];
            script(socket_, client, request);
          }
        }) {}
  ~NatNetScriptedServer() {
    done_ = true;
    boost::system::error_code ec;
    udp::socket poke(io_, udp::v4());
    poke.send_to(asio::buffer("x", 1), socket_.local_endpoint(), 0, ec);  // wakes receive_from()
    thread_.join();
  }
  uint16_t port() const { return socket_.local_endpoint().port(); }
  std::array<std::atomic<int>, 16> requests{};

 private:
  asio::io_context io_;
  udp::socket socket_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

natnet::ByteVector unicast_info() {
  natnet::ServerInfo info;
  info.multicast = false;
  return natnet::encode_server_info(info);
}

TEST(NatNetSource, MalformedTruncatedAndUnknownInputIsReportedAndSurvived) {
  const Capture walker = test::replay_capture(10, 0.0);
  natnet::CaptureEncoder encoder({{"walker", &walker}});
  natnet::CaptureEncoder stranger_encoder({{"stranger", &walker}});
  int answered_definitions = 0;
  NatNetScriptedServer server([&](udp::socket& s, const udp::endpoint& client, uint16_t request) {
    if (request == natnet::message::Connect) {
      s.send_to(asio::buffer(natnet::ByteVector{1, 0, 0xFF, 0xFF}), client);  // byte count past the datagram
      s.send_to(asio::buffer(unicast_info()), client);
    } else if (request == natnet::message::RequestModelDef) {
      s.send_to(asio::buffer(natnet::encode_model_definitions(encoder.model_definitions(), {4, 1})), client);
      if (answered_definitions++ > 0) return;  // the frames follow the first definitions only
      natnet::ByteVector frame;
      encoder.encode(1, {4, 1}, frame);
      natnet::ByteVector truncated(frame.begin(), frame.begin() + 40);
      truncated[2] = 36;  // a consistent header, a payload cut short
      truncated[3] = 0;
      s.send_to(asio::buffer(truncated), client);
      stranger_encoder.encode(2, {4, 1}, frame);  // a marker set the definitions do not describe
      s.send_to(asio::buffer(frame), client);
      for (uint64_t k = 3; k < 6; ++k) {
        encoder.encode(k, {4, 1}, frame);
        s.send_to(asio::buffer(frame), client);
      }
    }
  });
  IoThread client_io;
  SourceSinkRecorder sink;
  NatNetSourceOptions options = natnet_client_of(server.port());
  options.stall_timeout = 5s;  // the script goes quiet after its frames: no reconnection here
  options.model_request_interval = 0ms;
  NatNetSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(4));
  ASSERT_TRUE(sink.wait_bad_input("unknown_marker_set"));
  ASSERT_TRUE(test::eventually([&] { return server.requests[natnet::message::RequestModelDef] >= 2; }));
  source.stop();
  client_io.call([] {});
  std::lock_guard lock(sink.mutex);
  int malformed = 0, unknown = 0;
  for (const std::string& b : sink.bad_inputs) {
    malformed += b.rfind("malformed_packet:", 0) == 0;
    unknown += b.rfind("unknown_marker_set:", 0) == 0;
  }
  EXPECT_EQ(malformed, 2);  // the bad header and the truncated frame
  EXPECT_EQ(unknown, 1);
  EXPECT_FALSE(is_present(sink.frames[0].labelled[0][0]));  // the stranger's frame: walker not in it
  EXPECT_EQ(sink.frames[1].frame_number, 103u);
  EXPECT_EQ(sink.count_state(SourceState::Disconnected), 0u);
}

TEST(NatNetSource, NoAnswerAndOldServersDisconnect) {
  NatNetScriptedServer silent([](udp::socket&, const udp::endpoint&, uint16_t) {});
  NatNetScriptedServer old([](udp::socket& s, const udp::endpoint& client, uint16_t request) {
    if (request != natnet::message::Connect) return;
    natnet::ServerInfo info;
    info.natnet_version = {2, 9, 0, 0};
    s.send_to(asio::buffer(natnet::encode_server_info(info)), client);
  });
  IoThread client_io;
  SourceSinkRecorder a, b;
  NatNetSource to_silent(client_io.io, natnet_client_of(silent.port()), a);
  NatNetSource to_old(client_io.io, natnet_client_of(old.port()), b);
  to_silent.start();
  to_old.start();
  ASSERT_TRUE(a.wait_state(SourceState::Disconnected));
  ASSERT_TRUE(b.wait_state(SourceState::Disconnected));
  ASSERT_TRUE(test::eventually([&] { return silent.requests[natnet::message::Connect] >= 2; }));  // tried again
  to_silent.stop();
  to_old.stop();
  client_io.call([] {});
  EXPECT_NE(a.last_detail(SourceState::Disconnected).find("no server info"), std::string::npos);
  EXPECT_NE(b.last_detail(SourceState::Disconnected).find("NatNet 2.9"), std::string::npos);
}

// A server that answers the handshake and its first frames, then goes silent (its keep-alives
// unanswered, as a server whose stream stopped): stalled, and asked again.
TEST(NatNetSource, AServerThatGoesSilentIsStalledAndAskedAgain) {
  test::SilentNatNetServer silent({.frames = 5});
  IoThread client_io;
  SourceSinkRecorder sink;
  NatNetSource source(client_io.io, natnet_client_of(silent.port()), sink);
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

// This process's UDP socket bound to `port`: its local address ("" when there is none).
std::string udp_address_of_port(uint16_t port) {
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    const int fd = std::stoi(entry.path().filename().string());
    int type = 0;
    socklen_t type_length = sizeof type;
    sockaddr_in own{};
    socklen_t own_length = sizeof own;
    if (::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_length) != 0 || type != SOCK_DGRAM) continue;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&own), &own_length) != 0 || own.sin_family != AF_INET) continue;
    if (ntohs(own.sin_port) == port) return asio::ip::address_v4(ntohl(own.sin_addr.s_addr)).to_string();
  }
  return "";
}

// Unicast: a stranger on another port (here, of the same host) sends the client model
// definitions of another marker set and frames of its own. The client was bound to 0.0.0.0 and
// took them (the subject went absent; 200 forged frames were taken): now its socket is bound to
// the address toward the server and takes the server's datagrams only, counting the others.
TEST(NatNetSource, UnicastTakesTheServersDatagramsOnly) {
  const Capture walker = test::replay_capture(10, 0.0);
  natnet::CaptureEncoder encoder({{"walker", &walker}});
  natnet::CaptureEncoder stranger_encoder({{"stranger", &walker}});
  asio::io_context stranger_io;
  udp::socket stranger(stranger_io, udp::endpoint(asio::ip::make_address("127.0.0.2"), 0));
  std::atomic<uint16_t> client_port{0};
  NatNetScriptedServer server([&](udp::socket& s, const udp::endpoint& client, uint16_t request) {
    client_port = client.port();
    natnet::ByteVector frame;
    if (request == natnet::message::Connect) {
      s.send_to(asio::buffer(unicast_info()), client);
    } else if (request == natnet::message::RequestModelDef) {
      s.send_to(asio::buffer(natnet::encode_model_definitions(encoder.model_definitions(), {4, 1})), client);
      for (uint64_t k = 0; k < 3; ++k) {
        encoder.encode(k, {4, 1}, frame);
        s.send_to(asio::buffer(frame), client);
      }
      // The stranger: other definitions, then frames numbered far from the server's.
      stranger.send_to(asio::buffer(natnet::encode_model_definitions(stranger_encoder.model_definitions(), {4, 1})), client);
      for (uint64_t k = 1000; k < 1100; ++k) {
        stranger_encoder.encode(k, {4, 1}, frame);
        stranger.send_to(asio::buffer(frame), client);
      }
      for (uint64_t k = 3; k < 6; ++k) {
        encoder.encode(k, {4, 1}, frame);
        s.send_to(asio::buffer(frame), client);
      }
    }
  });
  IoThread client_io;
  SourceSinkRecorder sink;
  NatNetSourceOptions options = natnet_client_of(server.port());
  options.stall_timeout = 5s;
  NatNetSource source(client_io.io, options, sink);
  source.start();
  ASSERT_TRUE(sink.wait_frames(6));
  ASSERT_TRUE(sink.wait([&] { return sink.bad_inputs.size() >= 101; }));
  const std::string bound = udp_address_of_port(client_port);
  source.stop();
  client_io.call([] {});
  std::lock_guard lock(sink.mutex);
  EXPECT_EQ(bound, "127.0.0.1");
  ASSERT_EQ(sink.frames.size(), 6u);
  for (const SourceFrame& f : sink.frames) {
    EXPECT_LT(f.frame_number, 106u);
    ASSERT_EQ(f.subjects.size(), 1u);
    EXPECT_EQ(f.subjects[0].name, "walker");
  }
  EXPECT_EQ(sink.bad_inputs.size(), 101u);
  for (const std::string& b : sink.bad_inputs)
    EXPECT_EQ(b.rfind("foreign_datagram: NatNet: dropped a datagram from 127.0.0.2, not the server 127.0.0.1", 0), 0u) << b;
}

TEST(NatNetServer, CountsMalformedDatagramsAndAnswersTheRest) {
  const Capture walker = test::replay_capture(10, 0.0);
  IoThread server_io;
  NatNetServer server(server_io.io, {{"walker", &walker}}, unicast_server({3, 1}));
  server_io.call([&] { server.start(); });
  asio::io_context io;
  udp::socket s(io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  const udp::endpoint to(asio::ip::make_address("127.0.0.1"), server_io.call([&] { return server.command_port(); }));
  s.send_to(asio::buffer(natnet::ByteVector{4, 0, 9, 0}), to);  // 9 bytes announced, none follow
  s.send_to(asio::buffer(natnet::ByteVector{1}), to);            // shorter than a header
  s.send_to(asio::buffer(natnet::encode_connect("test", {3, 1})), to);
  s.send_to(asio::buffer(natnet::encode_empty(natnet::message::RequestModelDef)), to);
  s.send_to(asio::buffer(natnet::encode_text(natnet::message::Request, "TimelinePlay")), to);
  std::vector<unsigned char> buffer(natnet::kMaxMessageBytes);
  udp::endpoint from;
  uint16_t id = 0;
  natnet::Bytes payload;
  std::string error;
  const size_t n0 = s.receive_from(asio::buffer(buffer), from);  // the server info
  ASSERT_TRUE(natnet::read_message({buffer.data(), n0}, id, payload, error)) << error;
  EXPECT_EQ(id, natnet::message::ServerInfo);
  // The next answer that is not a frame (the timeline started with the CONNECT).
  auto next_answer = [&] {
    for (;;) {
      const size_t n = s.receive_from(asio::buffer(buffer), from);
      if (!natnet::read_message({buffer.data(), n}, id, payload, error)) return false;
      if (id != natnet::message::FrameOfData) return true;
    }
  };
  ASSERT_TRUE(next_answer()) << error;  // the model definitions
  EXPECT_EQ(id, natnet::message::ModelDef);
  natnet::ModelDefinitions defs;
  ASSERT_TRUE(natnet::decode_model_definitions(payload, {3, 1}, defs, error)) << error;
  EXPECT_EQ(defs.marker_sets[0].markers, (std::vector<std::string>{"A", "B"}));
  ASSERT_TRUE(next_answer()) << error;
  EXPECT_EQ(id, natnet::message::UnrecognizedRequest);
  EXPECT_EQ(server.stats().bad_datagrams.load(), 2u);
  server_io.call([&] { server.stop(); });
}

// A model request costs 4 bytes and its answer ~1,000 times that: answered only to a sender that
// CONNECTed (a forged source address would have the server flood a victim). And CONNECTs from
// many ports (2,000 once starved the real client of frames for 10 s) beyond max_clients are
// not answered: the clients already served keep their frames.
TEST(NatNetServer, AnswersRequestsOnlyToConnectedClientsAndServesAFew) {
  const Capture walker = test::replay_capture(10, 0.0);
  IoThread server_io;
  NatNetServerOptions options = unicast_server({4, 1});
  options.max_clients = 4;
  NatNetServer server(server_io.io, {{"walker", &walker}}, options);
  server_io.call([&] { server.start(); });
  const udp::endpoint to(asio::ip::make_address("127.0.0.1"), server_io.call([&] { return server.command_port(); }));
  asio::io_context io;
  auto answered = [&](udp::socket& s) {
    s.non_blocking(true);
    std::vector<unsigned char> buffer(natnet::kMaxMessageBytes);
    udp::endpoint from;
    boost::system::error_code ec;
    for (auto end = std::chrono::steady_clock::now() + 500ms; std::chrono::steady_clock::now() < end;) {
      if (s.receive_from(asio::buffer(buffer), from, 0, ec) > 0) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  };
  udp::socket stranger(io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  stranger.send_to(asio::buffer(natnet::encode_empty(natnet::message::RequestModelDef)), to);
  EXPECT_FALSE(answered(stranger)) << "a model request answered to a sender that never connected";
  std::vector<std::unique_ptr<udp::socket>> clients;
  for (int i = 0; i < 6; ++i) {
    clients.push_back(std::make_unique<udp::socket>(io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0)));
    clients.back()->send_to(asio::buffer(natnet::encode_connect("test", {4, 1})), to);
    EXPECT_EQ(answered(*clients.back()), i < 4) << "client " << i;
  }
  EXPECT_EQ(server.stats().clients_refused.load(), 2u);
  EXPECT_EQ(server.stats().requests_not_connected.load(), 1u);
  EXPECT_EQ(server.stats().clients_connected.load(), 4u);
  server_io.call([&] { server.stop(); });
}

}  // namespace
}  // namespace skinstream::server
