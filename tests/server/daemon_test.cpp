// The daemon in-process on real loopback sockets: a replayed take goes through the pipeline to
// TCP and WebSocket subscribers; a stalled subscriber does not hold back the others; a paced
// subscriber never has more than its window in flight; the filled markers equal the offline
// fill of the same take frame by frame.
#include "server/daemon.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "core/capture_filler.h"
#include "core/offline/subject_builder.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_packet_writer.h"
#include "server/beast.h"
#include "server/publish/subscriber_hub.h"
#include "server/tcp_congestion.h"
#include "support/loopback_config.h"
#include "support/socket_lookup.h"
#include "support/stalled_subscriber.h"
#include "support/subscriber_client.h"
#include "support/test_data.h"
#include "support/thread_names.h"
#include "support/wait_until.h"

namespace skinstream::server {
namespace {

struct Fixture {
  std::string subject_path, take_path;
  SubjectModel model;
  Capture take;
};

// A subject trained on CMU 85_02 and 360 frames of 85_12 to replay (3 s), made once.
const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture out;
    // Per process: ctest runs each test in its own process, several at once.
    const std::string own = std::to_string(getpid());
    out.subject_path = test::scratch_path("daemon_subject_" + own + ".sks");
    out.take_path = test::scratch_path("daemon_take_" + own + ".c3d");
    out.model = build_subject(read_capture(test::source_path("replay_data/cmu/85_02.c3d")), {});
    write_subject(out.model, out.subject_path);
    const Capture full = read_capture(test::source_path("replay_data/cmu/85_12.c3d"));
    std::vector<int> channels(full.point_count());
    for (int c = 0; c < full.point_count(); ++c) channels[c] = c;
    out.take = full.select(channels, 0, 360);
    write_capture(out.take, out.take_path);
    out.take = read_capture(out.take_path);  // exactly what the daemon reads
    return out;
  }();
  return f;
}

DaemonConfig test_config() {
  DaemonConfig config = test::loopback_config();
  config.subjects = {{"", fixture().subject_path}};
  config.replay = fixture().take_path;
  return config;
}

using test::wait_until;

std::string http_get(int port, const std::string& target, int* out_status = nullptr) {
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)));
  http::request<http::empty_body> request{http::verb::get, target, 11};
  request.set(http::field::host, "127.0.0.1");
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response<http::string_body> response;
  http::read(stream, buffer, response);
  if (out_status) *out_status = static_cast<int>(response.result_int());
  return response.body();
}

TEST(Daemon, MissingSubjectFailsClearly) {
  DaemonConfig config = test_config();
  config.subjects = {{"", test::scratch_path("absent.sks")}};
  try {
    Daemon daemon(config);
    FAIL() << "started without a subject";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("absent.sks"), std::string::npos) << e.what();
  }
}

TEST(Daemon, NamedSubjectIsTheReplaysOneSubject) {
  DaemonConfig config = test_config();
  config.subjects = {{"Actor1", fixture().subject_path}};
  try {
    Daemon daemon(config);
    FAIL() << "followed a subject the replay does not have";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("subject \"Actor1\" is not in the replay"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--replay-subject"), std::string::npos) << e.what();
  }
  config.replay_subject = "Actor1";
  Daemon daemon(config);
  daemon.start();
  wait_until([&] { return nlohmann::json::parse(daemon.health_json())["frames"]["processed"].get<int>() > 0; });
  const nlohmann::json subject = nlohmann::json::parse(daemon.health_json())["subject"];
  daemon.stop();
  EXPECT_EQ(subject["name"], "Actor1");
  EXPECT_TRUE(subject["present"].get<bool>());
  EXPECT_EQ(subject["detail"], "follows \"Actor1\": 41 of the subject's 41 markers labelled");
}

TEST(Daemon, PortInUseFailsClearly) {
  Daemon first(test_config());
  DaemonConfig config = test_config();
  config.sub_port = first.sub_port();
  try {
    Daemon second(config);
    FAIL() << "two daemons on one port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(first.sub_port())), std::string::npos) << e.what();
  }
}

TEST(Daemon, PublishesTheOfflineFillFrameByFrameInOrder) {
  DaemonConfig config = test_config();
  config.subscriber_queue_frames = 64;  // this test wants every frame; back-pressure is tested below
  config.max_frame_wait_ms = 1000;
  Daemon daemon(config);
  std::vector<subscriber::Frame> frames;
  subscriber::MeshInfo mesh_info;
  std::thread reader([&] {
    sub::SubscriberClient client("127.0.0.1", std::to_string(daemon.sub_port()), subscriber::kWantMarkers);
    client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) {
      if (type == subscriber::MessageType::MeshInfo) mesh_info = subscriber::decode_mesh_info(payload);
      if (type == subscriber::MessageType::Frame) frames.push_back(subscriber::decode_frame(payload));
      // A dropped frame never comes: stop at the first sign of one instead of waiting forever.
      return frames.size() < 360u && (frames.empty() || (frames.back().info.pipeline_dropped == 0 && frames.back().info.subscriber_dropped == 0));
    });
  });
  // The replay starts only once the subscriber listens, so it sees the take from its first frame.
  daemon.start_serving();
  wait_until([&] { return !daemon.subject(0).hub().wanted_encodings().empty(); });
  daemon.start_source();
  reader.join();
  daemon.stop();

  const Fixture& f = fixture();
  EXPECT_EQ(mesh_info.vertex_count, 0u);  // no deformation model: markers only
  EXPECT_EQ(mesh_info.marker_names, f.model.marker_names);
  ASSERT_FALSE(frames.empty());
  if (frames.back().info.pipeline_dropped != 0 || frames.back().info.subscriber_dropped != 0)
    GTEST_SKIP() << "a frame was dropped (pipeline " << frames.back().info.pipeline_dropped << ", subscriber "
                 << frames.back().info.subscriber_dropped << "): the machine is too busy for a frame-by-frame comparison";
  ASSERT_EQ(frames.size(), 360u);
  std::vector<MarkerStatus> status;
  const Capture offline = fill_capture(f.model, f.take, {}, &status);
  const int n = f.model.marker_count();
  for (size_t i = 0; i < frames.size(); ++i) {
    const subscriber::Frame& frame = frames[i];
    if (frame.info.pipeline_dropped != 0)
      GTEST_SKIP() << "the pipeline thread was descheduled and a frame was overwritten (machine too busy); the fill history differs";
    ASSERT_EQ(frame.info.frame_number, static_cast<uint32_t>(f.take.first_frame + static_cast<int>(i)));
    ASSERT_EQ(frame.info.flags, subscriber::kFrameMarkers | subscriber::kFrameNoPositions);
    ASSERT_LE(frame.info.receive_time_ns, frame.info.publish_time_ns);
    for (int m = 0; m < n; ++m) {
      for (int a = 0; a < 3; ++a)
        ASSERT_NEAR(frame.markers[3 * m + a], offline.at(static_cast<int>(i), m)[a], 1e-3 * std::max(1.0, std::abs(offline.at(static_cast<int>(i), m)[a])))
            << "frame " << i << " marker " << m;
      ASSERT_EQ(frame.marker_status[m], static_cast<uint8_t>(status[i * n + m])) << "frame " << i << " marker " << m;
    }
  }
}

TEST(Daemon, StalledSubscriberDoesNotHoldBackTheOthers) {
  DaemonConfig config = test_config();
  config.speed = 4;
  config.loop = true;
  config.subscriber_queue_frames = 256;  // the healthy subscriber never needs more
  config.max_frame_wait_ms = 1000;       // nor waits that long on a busy machine
  Daemon daemon(config);
  daemon.start_serving();

  // The stalled subscriber asks for markers and never reads.
  asio::io_context io;
  tcp::socket stalled = test::stalled_subscriber(io, daemon.sub_port(), subscriber::encode_hello({.wants = subscriber::kWantMarkers}));
  wait_until([&] { return !daemon.subject(0).hub().wanted_encodings().empty(); });

  daemon.start_source();
  long received = 0;
  int64_t last = -1;
  uint32_t last_pipeline_dropped = 0;
  bool in_order = true;
  uint32_t own_drops = 0;
  auto stalled_dropped = [&] {
    uint64_t most = 0;
    for (const SubscriberMetrics& s : daemon.subject(0).hub().subscriber_metrics()) most = std::max(most, s.dropped);
    return most;
  };
  sub::SubscriberClient client("127.0.0.1", std::to_string(daemon.sub_port()), subscriber::kWantMarkers);
  client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) {
    if (type != subscriber::MessageType::Frame) return true;
    const subscriber::Frame frame = subscriber::decode_frame(payload);
    // The replay loops: numbers rise except when it starts again at the first frame, or at a
    // later one when the pipeline overwrote the first frames of the new loop (a busy machine;
    // the frames it dropped are counted in pipeline_dropped, not lost by this subscriber).
    if (static_cast<int64_t>(frame.info.frame_number) <= last) {
      const int64_t into_loop = static_cast<int64_t>(frame.info.frame_number) - fixture().take.first_frame;
      if (into_loop < 0 || into_loop > static_cast<int64_t>(frame.info.pipeline_dropped - last_pipeline_dropped)) in_order = false;
    }
    last = frame.info.frame_number;
    last_pipeline_dropped = frame.info.pipeline_dropped;
    own_drops = frame.info.subscriber_dropped;
    ++received;
    // Run until the stalled subscriber has lost a good number of frames.
    return stalled_dropped() < 500;
  });
  EXPECT_TRUE(in_order);
  EXPECT_EQ(own_drops, 0u);
  EXPECT_GT(received, 500);
  const std::string metrics = http_get(daemon.http_port(), "/metrics");
  EXPECT_NE(metrics.find("skinstream_subscriber_frames_dropped_total{"), std::string::npos);
  daemon.stop();
}

// TCP subscribers on the publish threads (three threads, four subscribers) and on the io thread
// (publish_threads 0) each get every frame in order; stopping the daemon with a subscriber
// still connected and not reading closes it on its own thread and returns.
class DaemonPublishThreads : public ::testing::TestWithParam<int> {};

TEST_P(DaemonPublishThreads, EverySubscriberGetsEveryFrameInOrderAndStopClosesTheRest) {
  DaemonConfig config = test_config();
  config.publish_threads = GetParam();
  config.subscriber_queue_frames = 64;
  config.max_frame_wait_ms = 1000;
  Daemon daemon(config);
  daemon.start_serving();
  EXPECT_EQ(nlohmann::json::parse(daemon.health_json())["publish_threads"].get<int>(), GetParam());

  asio::io_context io;  // the subscriber that never reads: still connected at stop()
  tcp::socket idle(io);
  idle.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.sub_port())));
  asio::write(idle, asio::buffer(subscriber::encode_hello({.wants = subscriber::kWantMarkers})));

  constexpr int kSubscribers = 4;
  constexpr size_t kFrames = 120;
  std::vector<std::vector<uint32_t>> numbers(kSubscribers);
  std::vector<uint32_t> dropped(kSubscribers, 0);
  std::vector<std::thread> readers;
  for (int s = 0; s < kSubscribers; ++s)
    readers.emplace_back([&, s] {
      sub::SubscriberClient client("127.0.0.1", std::to_string(daemon.sub_port()), subscriber::kWantMarkers);
      client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) {
        if (type != subscriber::MessageType::Frame) return true;
        const subscriber::FrameInfo info = subscriber::decode_frame_info(payload);
        numbers[s].push_back(info.frame_number);
        dropped[s] = info.pipeline_dropped + info.subscriber_dropped;
        return numbers[s].size() < kFrames;
      });
    });
  wait_until([&] { return daemon.subject(0).hub().subscriber_count() == kSubscribers + 1 && !daemon.subject(0).hub().wanted_encodings().empty(); });
  daemon.start_source();
  for (std::thread& t : readers) t.join();
  daemon.stop();

  for (int s = 0; s < kSubscribers; ++s) {
    ASSERT_EQ(numbers[s].size(), kFrames) << "subscriber " << s;
    if (dropped[s] != 0) GTEST_SKIP() << "a frame was dropped: the machine is too busy for a frame-by-frame check";
    for (size_t i = 1; i < kFrames; ++i)
      ASSERT_EQ(numbers[s][i], numbers[s][i - 1] + 1) << "subscriber " << s << " frame " << i;
  }
  // The idle subscriber's connection was closed by the daemon: it reads what was sent, then EOF.
  boost::system::error_code ec;
  std::array<unsigned char, 65536> buffer;
  while (!ec) idle.read_some(asio::buffer(buffer), ec);
  EXPECT_TRUE(ec == asio::error::eof || ec == asio::error::connection_reset) << ec.message();
}

INSTANTIATE_TEST_SUITE_P(Threads, DaemonPublishThreads, ::testing::Values(0, 3));

// `top -H` on a stage machine tells the daemon's threads apart: each names itself (this
// subject has no mesh, so there is no deform worker; deform_workers_test checks those).
TEST(Daemon, NamesItsThreads) {
  DaemonConfig config = test_config();
  config.publish_threads = 2;
  Daemon daemon(config);
  daemon.start_serving();
  const char* const expected[] = {"io", "pipeline", "publish-0", "publish-1"};
  std::multiset<std::string> names;
  // Each thread names itself once it runs, in no set order: wait for all of them.
  wait_until([&] {
    names = test::process_thread_names();
    return std::all_of(std::begin(expected), std::end(expected), [&](const char* name) { return names.count(name) == 1; });
  });
  daemon.stop();
  for (const char* name : expected) EXPECT_EQ(names.count(name), 1u) << name;
}

// Reads a raw subscriber socket, decoding Frames, until `deadline` or until `enough` frames
// have come (0: no such limit).
std::vector<subscriber::Frame> read_frames_until(tcp::socket& socket, subscriber::StreamDecoder& decoder,
                                                 std::chrono::steady_clock::time_point deadline, size_t enough = 0) {
  std::vector<subscriber::Frame> frames;
  std::array<unsigned char, 65536> buffer;
  while (std::chrono::steady_clock::now() < deadline && (enough == 0 || frames.size() < enough)) {
    if (socket.available() == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    decoder.feed(std::span(buffer).first(socket.read_some(asio::buffer(buffer))));
    while (auto m = decoder.next())
      if (m->type == subscriber::MessageType::Frame) frames.push_back(subscriber::decode_frame(m->payload));
  }
  return frames;
}

TEST(Daemon, PacedSubscriberHasAtMostTheWindowInFlightAndGetsTheNewestFrameOnAck) {
  DaemonConfig config = test_config();
  config.speed = 4;  // 480 frames a second
  config.loop = true;
  Daemon daemon(config);
  daemon.start_serving();
  asio::io_context io;
  tcp::socket paced(io);
  paced.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.sub_port())));
  asio::write(paced, asio::buffer(subscriber::encode_hello({.wants = subscriber::kWantMarkers | subscriber::kWantPaced})));
  wait_until([&] { return !daemon.subject(0).hub().wanted_encodings().empty(); });
  daemon.start_source();
  subscriber::StreamDecoder decoder;
  using std::chrono::milliseconds;

  // Frames now and in the next 300 ms (another ~140 are published meanwhile).
  auto frames_then_quiet = [&](size_t expected) {
    std::vector<subscriber::Frame> got =
        read_frames_until(paced, decoder, std::chrono::steady_clock::now() + std::chrono::seconds(10), expected);
    const std::vector<subscriber::Frame> more = read_frames_until(paced, decoder, std::chrono::steady_clock::now() + milliseconds(300));
    got.insert(got.end(), more.begin(), more.end());
    return got;
  };
  // No Ack: the window's frames come, then nothing.
  std::vector<subscriber::Frame> first = frames_then_quiet(subscriber::kPacedWindow);
  ASSERT_EQ(first.size(), static_cast<size_t>(subscriber::kPacedWindow));
  EXPECT_LT(first[0].info.frame_number, first[1].info.frame_number);

  // One Ack frees one slot: exactly one frame, the newest (the ones in between were dropped).
  asio::write(paced, asio::buffer(subscriber::encode_ack({first[0].info.frame_number})));
  std::vector<subscriber::Frame> next = frames_then_quiet(1);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_GT(next[0].info.subscriber_dropped, 0u);
  EXPECT_NE(next[0].info.frame_number, first[1].info.frame_number + 1);

  // Acking every frame keeps the stream going, in order (apart from the loop's restart).
  asio::write(paced, asio::buffer(subscriber::encode_ack({first[1].info.frame_number})));
  asio::write(paced, asio::buffer(subscriber::encode_ack({next[0].info.frame_number})));
  long received = 0;
  const auto end = std::chrono::steady_clock::now() + milliseconds(1000);
  std::array<unsigned char, 65536> buffer;
  while (std::chrono::steady_clock::now() < end) {
    decoder.feed(std::span(buffer).first(paced.read_some(asio::buffer(buffer))));
    while (auto m = decoder.next()) {
      if (m->type != subscriber::MessageType::Frame) continue;
      ++received;
      asio::write(paced, asio::buffer(subscriber::encode_ack({subscriber::decode_frame(m->payload).info.frame_number})));
    }
  }
  EXPECT_GT(received, 50);
  daemon.stop();
}

TEST(Daemon, ServesHealthMetricsWebSocketAndSubscribersWithoutHello) {
  Daemon daemon(test_config());
  daemon.start();
  // A subscriber that never says Hello gets positions-only frames after the timeout.
  asio::io_context io;
  tcp::socket silent(io);
  silent.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.sub_port())));
  subscriber::StreamDecoder decoder;
  std::array<unsigned char, 4096> buffer;
  bool got_frame = false, got_mesh_info = false;
  while (!got_frame) {
    decoder.feed(std::span(buffer).first(silent.read_some(asio::buffer(buffer))));
    while (auto m = decoder.next()) {
      if (m->type == subscriber::MessageType::MeshInfo) got_mesh_info = true;
      if (m->type == subscriber::MessageType::Frame) {
        EXPECT_TRUE(got_mesh_info);
        EXPECT_EQ(subscriber::decode_frame(m->payload).info.flags, subscriber::kFrameNoPositions);
        got_frame = true;
      }
    }
  }

  // WebSocket at /stream: one protocol message per binary message.
  websocket::stream<beast::tcp_stream> ws(io);
  beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.http_port())));
  ws.handshake("127.0.0.1", "/stream");
  ws.binary(true);
  ws.write(asio::buffer(subscriber::encode_hello({.wants = subscriber::kWantMarkers})));
  bool ws_frame = false;
  for (int i = 0; i < 20 && !ws_frame; ++i) {
    beast::flat_buffer message;
    ws.read(message);
    const std::span<const unsigned char> bytes(static_cast<const unsigned char*>(message.cdata().data()), message.size());
    const subscriber::MessageHeader header = subscriber::decode_header(bytes);
    EXPECT_EQ(header.payload_bytes + subscriber::kHeaderBytes, bytes.size());
    if (header.type == subscriber::MessageType::Frame)
      ws_frame = subscriber::decode_frame(bytes.subspan(subscriber::kHeaderBytes)).info.flags & subscriber::kFrameMarkers;
  }
  EXPECT_TRUE(ws_frame);

  // A subscriber that sends anything but Hello is disconnected and counted.
  tcp::socket rude(io);
  rude.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.sub_port())));
  asio::write(rude, asio::buffer(subscriber::encode_status({})));
  boost::system::error_code ec;
  while (!ec) rude.read_some(asio::buffer(buffer), ec);  // until the daemon closes it
  EXPECT_EQ(daemon.subject(0).metrics().bad_subscriber_messages.load(), 1u);

  int status = 0;
  const nlohmann::json health = nlohmann::json::parse(http_get(daemon.http_port(), "/health", &status));
  EXPECT_EQ(status, 200);
  EXPECT_GT(health["frames"]["received"].get<long>(), 0);
  EXPECT_LE(health["frames"]["dropped_mailbox_full"].get<uint64_t>(), health["frames"]["dropped"].get<uint64_t>());
  EXPECT_GE(health["subscribers"].get<int>(), 2);
  EXPECT_EQ(health["source_limits"]["max_subjects"].get<int>(), DaemonConfig{}.source_max_subjects);
  EXPECT_EQ(health["source_limits"]["max_markers_per_subject"].get<int>(), DaemonConfig{}.source_max_markers_per_subject);
  EXPECT_EQ(health["source_limits"]["max_name_bytes"].get<int>(), DaemonConfig{}.source_max_name_bytes);
  // Frames went out, so encoded buffers exist (the counter only grows, and frames keep coming).
  EXPECT_GE(health["frame_buffers_allocated"].get<long>(), 1);
  EXPECT_LE(health["frame_buffers_allocated"].get<uint64_t>(), daemon.subject(0).metrics().frame_buffers_allocated.load());
  // Every stage summarised for scripts, each summary ordered. Frames were filled, encoded and
  // written to subscribers; this subject has no mesh, so nothing was deformed.
  for (const char* stage : {"receive_to_take", "fill", "deform", "normals", "encode", "receive_to_publish",
                            "subscriber_queue_wait", "subscriber_write"}) {
    SCOPED_TRACE(stage);
    const nlohmann::json& h = health["latency_ms"][stage];
    const std::string name = stage;
    if (name == "deform" || name == "normals")
      EXPECT_EQ(h["count"].get<uint64_t>(), 0u);
    else
      EXPECT_GT(h["count"].get<uint64_t>(), 0u);
    EXPECT_LE(h["p50_le"].get<double>(), h["p99_le"].get<double>());
    EXPECT_LE(h["p99_le"].get<double>(), h["p99_9_le"].get<double>());
    EXPECT_LE(h["p99_9_le"].get<double>(), h["max"].get<double>());
  }
  const std::string metrics = http_get(daemon.http_port(), "/metrics", &status);
  EXPECT_EQ(status, 200);
  // The source's frames unlabelled, the subject's series labelled with its name.
  const std::string subject = "{subject=\"" + daemon.subject(0).name() + "\"";
  EXPECT_NE(metrics.find("skinstream_source_frames_total "), std::string::npos);
  for (const char* name : {"skinstream_frames_received_total", "skinstream_frames_published_total", "skinstream_frames_dropped_total",
                           "skinstream_frames_dropped_mailbox_full_total", "skinstream_markers_filled_total", "skinstream_encode_seconds_count",
                           "skinstream_receive_to_take_seconds_count", "skinstream_subscriber_queue_wait_seconds_count",
                           "skinstream_subscriber_write_seconds_count"})
    EXPECT_NE(metrics.find(name + subject + "} "), std::string::npos) << name;
  EXPECT_NE(metrics.find("skinstream_fill_seconds_bucket" + subject + ",le=\"+Inf\"}"), std::string::npos);
  EXPECT_NE(metrics.find("skinstream_bad_subscriber_messages_total" + subject + "} 1"), std::string::npos);
  http_get(daemon.http_port(), "/nothing-here", &status);
  EXPECT_EQ(status, 404);
  http_get(daemon.http_port(), "/", &status);
  EXPECT_EQ(status, 404);  // no web root configured
  daemon.stop();
}

// Frames a source numbered but never delivered are counted, so an operator sees that the preview
// is not every frame: a Vicon source (written here) offers its types, ignores what the daemon
// asks, and pushes the take's frames numbered 1-20, then 24-40 (3 never sent), then 200000 on (a
// new numbering, as after the source restarted: no loss).
TEST(Daemon, CountsTheFrameNumbersTheSourceSkipped) {
  std::vector<uint32_t> numbers;
  for (uint32_t n = 1; n <= 20; ++n) numbers.push_back(n);
  for (uint32_t n = 24; n <= 40; ++n) numbers.push_back(n);
  for (uint32_t n = 200000; n < 200010; ++n) numbers.push_back(n);
  asio::io_context io;
  tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  DaemonConfig config = test::loopback_config();
  config.subjects = {{"", fixture().subject_path}};
  config.vicon = "127.0.0.1:" + std::to_string(acceptor.local_endpoint().port());
  Daemon daemon(config);
  daemon.start();
  tcp::socket source = acceptor.accept();
  asio::write(source, asio::buffer(vicon::encode_packet(vicon::CaptureFrameEncoder::offered_types())));
  vicon::CaptureFrameEncoder encoder(fixture().take, "subject");
  vicon::PacketWriter writer;
  for (size_t k = 0; k < numbers.size(); ++k) {
    encoder.encode_frame(k, numbers[k], k == 0, writer);
    const std::span<const unsigned char> packet = writer.finish();
    asio::write(source, asio::buffer(packet.data(), packet.size()));
  }
  nlohmann::json health;
  wait_until([&] {
    health = nlohmann::json::parse(http_get(daemon.http_port(), "/health"));
    return health["source"]["frames"].get<size_t>() == numbers.size();
  });
  EXPECT_EQ(health["source"]["frames_skipped"].get<uint64_t>(), 3u);
  EXPECT_EQ(health["source"]["renumberings"].get<uint64_t>(), 1u);
  const std::string metrics = http_get(daemon.http_port(), "/metrics");
  EXPECT_NE(metrics.find("\nskinstream_source_frames_skipped_total 3\n"), std::string::npos);
  EXPECT_NE(metrics.find("\nskinstream_source_renumberings_total 1\n"), std::string::npos);
  daemon.stop();
}

// The subscriber protocol is binary (docs/subscriber-protocol.md): a Hello sent as a text message
// is refused with a close frame saying so (1003), and counted as a bad message.
TEST(Daemon, WebSocketTextMessageIsRefusedWithACloseAndCounted) {
  Daemon daemon(test_config());
  daemon.start();
  asio::io_context io;
  websocket::stream<beast::tcp_stream> ws(io);
  beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.http_port())));
  ws.handshake("127.0.0.1", "/stream");
  ws.text(true);
  ws.write(asio::buffer(subscriber::encode_hello({subscriber::kWantMarkers})));
  boost::system::error_code ec;
  for (int i = 0; i < 100 && !ec; ++i) {  // whatever was under way before the close, then the close
    beast::flat_buffer message;
    ws.read(message, ec);
  }
  EXPECT_EQ(ec, websocket::error::closed) << ec.message();
  EXPECT_EQ(ws.reason().code, websocket::close_code::unknown_data);
  EXPECT_EQ(std::string(ws.reason().reason.c_str()), "binary messages only");
  EXPECT_EQ(daemon.subject(0).metrics().bad_subscriber_messages.load(), 1u);
  daemon.stop();
}

// The congestion control the daemon gave a TCP subscriber and a WebSocket subscriber, each
// read once the daemon has sent it something (so it was accepted and set up).
std::pair<std::string, std::string> subscriber_congestion(const Daemon& daemon) {
  asio::io_context io;
  tcp::socket sub(io);
  sub.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.sub_port())));
  asio::write(sub, asio::buffer(subscriber::encode_hello({.wants = subscriber::kWantMarkers})));
  subscriber::StreamDecoder decoder;
  std::array<unsigned char, 4096> buffer;
  bool got_frame = false;
  while (!got_frame) {
    decoder.feed(std::span(buffer).first(sub.read_some(asio::buffer(buffer))));
    while (auto m = decoder.next()) got_frame = got_frame || m->type == subscriber::MessageType::Frame;
  }
  websocket::stream<beast::tcp_stream> ws(io);
  beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.http_port())));
  ws.handshake("127.0.0.1", "/stream");
  const int sub_fd = test::server_side_of(sub), ws_fd = test::server_side_of(beast::get_lowest_layer(ws).socket());
  EXPECT_GE(sub_fd, 0);
  EXPECT_GE(ws_fd, 0);
  return {tcp_congestion_of(sub_fd), tcp_congestion_of(ws_fd)};
}

TEST(Daemon, SubscriberConnectionsGetTheConfiguredCongestionControl) {
  {
    Daemon daemon(test_config());  // the default: reno, which does not pace sends
    daemon.start();
    EXPECT_EQ(nlohmann::json::parse(daemon.health_json())["subscriber_tcp_congestion"], "reno");
    EXPECT_EQ(subscriber_congestion(daemon), std::make_pair(std::string("reno"), std::string("reno")));
    daemon.stop();
  }
  DaemonConfig config = test_config();
  config.subscriber_tcp_congestion = "";  // the system's
  Daemon daemon(config);
  daemon.start();
  EXPECT_EQ(subscriber_congestion(daemon), std::make_pair(system_tcp_congestion(), system_tcp_congestion()));
  daemon.stop();
}

TEST(Daemon, RefusedCongestionControlStillServesEverySubscriber) {
  DaemonConfig config = test_config();
  config.subscriber_tcp_congestion = "no_such_cc";  // a valid name the kernel does not have
  Daemon daemon(config);
  daemon.start();
  // Frames still reach both kinds of subscriber, on the system's congestion control.
  EXPECT_EQ(subscriber_congestion(daemon), std::make_pair(system_tcp_congestion(), system_tcp_congestion()));
  daemon.stop();
}

}  // namespace
}  // namespace skinstream::server
