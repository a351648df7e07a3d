// The daemon with two subjects, in-process, fed by a Vicon DataStream server on loopback that
// streams two takes of one marker template as Actor1 and Actor2, 4 m apart: subscribers choose a
// subject in a version 2 Hello (version 1 gets the first); the actors never mix; a Hello naming a
// subject the daemon does not serve is refused; a subject leaves and returns; a stalled subscriber
// of one subject does not slow the other's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <atomic>
#include <nlohmann/json.hpp>
#include <thread>
#include <tuple>

#include "core/offline/subject_builder.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "protocol/vicon/vicon_capture_encoder.h"
#include "server/beast.h"
#include "server/daemon.h"
#include "server/replay/vicon/vicon_server.h"
#include "support/io_thread.h"
#include "support/loopback_config.h"
#include "support/recording_match.h"
#include "support/stalled_subscriber.h"
#include "support/subscriber_client.h"
#include "support/test_data.h"
#include "support/wait_until.h"

namespace skinstream::server {
namespace {

using test::wait_until;
constexpr double kApartMm = 4000.0;  // Actor2 stands this far from Actor1 along x
constexpr int kFrames = 360;
constexpr int kOffStageFrom = 120, kOffStageTo = 240;  // Actor2's frames without markers (in the leaving test)

struct Stage {
  std::string subject_path;
  Capture actor1, actor2, actor2_leaving;
};

// A subject trained on CMU 85_02; Actor1 performs 85_12, Actor2 85_02 moved 4 m along x (and,
// in actor2_leaving, off the stage for a while). Made once per process.
const Stage& stage() {
  static const Stage s = [] {
    Stage out;
    out.subject_path = test::scratch_path("stage_subject_" + std::to_string(getpid()) + ".sks");
    const Capture training = read_capture(test::source_path("replay_data/cmu/85_02.c3d"));
    write_subject(build_subject(training, {}), out.subject_path);
    std::vector<int> channels(static_cast<size_t>(training.point_count()));
    for (int c = 0; c < training.point_count(); ++c) channels[static_cast<size_t>(c)] = c;
    out.actor1 = read_capture(test::source_path("replay_data/cmu/85_12.c3d")).select(channels, 0, kFrames);
    out.actor2 = training.select(channels, 0, kFrames);
    out.actor2.first_frame = out.actor1.first_frame;  // one stream, one numbering
    for (int f = 0; f < kFrames; ++f)
      for (int c = 0; c < out.actor2.point_count(); ++c)
        if (out.actor2.present(f, c)) out.actor2.at(f, c) += Vec3(kApartMm, 0.0, 0.0);
    out.actor2_leaving = out.actor2;
    for (int f = kOffStageFrom; f < kOffStageTo; ++f)
      for (int c = 0; c < out.actor2.point_count(); ++c) out.actor2_leaving.at(f, c) = missing_point();
    return out;
  }();
  return s;
}

// The Vicon server streaming the two actors, looping, on its own io thread.
class StageServer {
 public:
  StageServer(const Capture& actor1, const Capture& actor2, double speed) {
    ViconServerOptions options;
    options.bind_address = "127.0.0.1";
    options.port = 0;
    options.speed = speed;
    options.loop = true;
    io_.call([&] {
      server_ = std::make_unique<ViconServer>(io_.io, std::vector<ReplaySubject>{{"Actor1", &actor1}, {"Actor2", &actor2}},
                                              options);
      server_->start();
      port_ = server_->port();
    });
  }
  ~StageServer() {
    io_.call([&] { server_.reset(); });  // the server belongs to its io thread
  }
  uint16_t port() const { return port_; }

 private:
  test::IoThread io_;
  std::unique_ptr<ViconServer> server_;
  uint16_t port_ = 0;
};

DaemonConfig stage_config(uint16_t vicon_port) {
  DaemonConfig config = test::loopback_config();
  config.subjects = {{"Actor1", stage().subject_path}, {"Actor2", stage().subject_path}};
  config.vicon = "127.0.0.1:" + std::to_string(vicon_port);
  return config;
}

subscriber::Hello hello_v2(const std::string& subject, uint32_t wants = subscriber::kWantMarkers,
                           subscriber::Encoding encoding = subscriber::Encoding::Float) {
  return {.wants = wants, .version = subscriber::kVersion2, .encoding = static_cast<uint32_t>(encoding), .subject = subject};
}

// What one subscriber received, decoded in the version of its Hello.
struct Received {
  std::vector<subscriber::MeshInfo> mesh_infos;
  std::vector<subscriber::Status> statuses;
  std::vector<size_t> frames_before_status;  // per Status, the frames received before it
  std::vector<subscriber::Frame> frames;
  bool closed_by_daemon = false;
};

// Subscribes with `hello` on its own connection until `done` says enough (or the daemon closes,
// or a minute passes: a Status comes every second, so a test waiting in vain fails, not hangs).
Received subscribe(const Daemon& daemon, const subscriber::Hello& hello, const std::function<bool(const Received&)>& done) {
  Received r;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  sub::SubscriberClient client("127.0.0.1", std::to_string(daemon.sub_port()), hello);
  r.closed_by_daemon = !client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) {
    if (std::chrono::steady_clock::now() > give_up) {
      ADD_FAILURE() << "the subscriber did not get what it waited for within 60 s";
      return false;
    }
    if (type == subscriber::MessageType::MeshInfo) r.mesh_infos.push_back(subscriber::decode_mesh_info(payload, hello.version));
    if (type == subscriber::MessageType::Status) {
      r.statuses.push_back(subscriber::decode_status(payload, hello.version));
      r.frames_before_status.push_back(r.frames.size());
    }
    if (type == subscriber::MessageType::Frame) r.frames.push_back(subscriber::decode_frame(payload, hello.version));
    return !done(r);
  });
  return r;
}

std::function<bool(const Received&)> frames_at_least(size_t n) {
  return [n](const Received& r) { return r.frames.size() >= n; };
}

// ... and a Status sent after the first frame: the one before it may predate the subject's
// first frame (subject not present yet) and, on a busy machine, be the only one in n frames.
std::function<bool(const Received&)> frames_and_a_later_status(size_t n) {
  return [n](const Received& r) {
    return r.frames.size() >= n && !r.frames_before_status.empty() && r.frames_before_status.back() > 0;
  };
}

TEST(DaemonSubjects, TwoActorsWithOneTemplateNeverMixAndEachSubscriberGetsTheSubjectItNamed) {
  StageServer server(stage().actor1, stage().actor2, 2.0);
  Daemon daemon(stage_config(server.port()));
  daemon.start();
  constexpr size_t kWanted = 150;
  Received first, second, version1;
  std::thread t1([&] { first = subscribe(daemon, hello_v2("Actor1"), frames_at_least(kWanted)); });
  std::thread t2([&] { second = subscribe(daemon, hello_v2("Actor2", subscriber::kWantMarkers, subscriber::Encoding::Quantised),
                                          frames_and_a_later_status(kWanted)); });
  version1 = subscribe(daemon, {.wants = subscriber::kWantMarkers}, frames_at_least(kWanted));
  t1.join();
  t2.join();
  // Each subject's rate of published frames, sampled about once a second while frames flow.
  nlohmann::json health;
  wait_until([&] {
    health = nlohmann::json::parse(daemon.health_json());
    return health["subjects"][0]["fps"].get<double>() > 0.0 && health["subjects"][1]["fps"].get<double>() > 0.0;
  });
  daemon.stop();

  // Each got its own subject's MeshInfo and Status, in its version.
  ASSERT_EQ(first.mesh_infos.size(), 1u);
  ASSERT_EQ(second.mesh_infos.size(), 1u);
  ASSERT_EQ(version1.mesh_infos.size(), 1u);
  EXPECT_EQ(first.mesh_infos[0].subject, "Actor1");
  EXPECT_EQ(second.mesh_infos[0].subject, "Actor2");
  // Quantised positions asked of a subject without a mesh: markers only, and so float.
  EXPECT_EQ(second.mesh_infos[0].encoding, subscriber::Encoding::Float);
  EXPECT_EQ(version1.mesh_infos[0].subject, "");  // version 1 MeshInfo has no subject
  ASSERT_FALSE(second.statuses.empty());
  EXPECT_EQ(second.statuses.back().subject, "Actor2");
  EXPECT_TRUE(second.statuses.back().subject_present);
  EXPECT_EQ(second.statuses.back().encoding, subscriber::Encoding::Float);

  // Version 2 frames carry the Vicon timecode (120 Hz: 24 fps film, 5 subframes); version 1's do not.
  for (const Received* r : {&first, &second}) {
    for (const subscriber::Frame& f : r->frames) {
      ASSERT_TRUE(f.info.flags & subscriber::kFrameTimecode) << f.info.flags;
      const vicon::Timecode sent = vicon::CaptureFrameEncoder::timecode_for(f.info.frame_number, 120.0);
      ASSERT_EQ(std::make_tuple(f.info.timecode.seconds, f.info.timecode.frames, f.info.timecode.subframe),
                std::make_tuple(sent.seconds, sent.frames, sent.subframes));
      ASSERT_EQ(f.info.timecode.rate_hz, 24.0f);
      ASSERT_EQ(f.info.timecode.subframes_per_frame, 5);
    }
  }
  for (const subscriber::Frame& f : version1.frames) ASSERT_EQ(f.info.flags, subscriber::kFrameMarkers | subscriber::kFrameNoPositions);

  // No marker of one actor ever reaches the other's frames: the measured samples are each one's
  // own, and every marker, measured or filled, lies nearer its own actor.
  test::RecordingMatch actor1(stage().actor1, kApartMm), actor2(stage().actor2, -kApartMm), actor1_v1(stage().actor1, kApartMm);
  for (const subscriber::Frame& f : first.frames) actor1.add(f.info.frame_number, f.markers);
  for (const subscriber::Frame& f : second.frames) actor2.add(f.info.frame_number, f.markers);
  for (const subscriber::Frame& f : version1.frames) actor1_v1.add(f.info.frame_number, f.markers);
  actor1.expect_measured_samples_unchanged();
  actor1_v1.expect_measured_samples_unchanged();
  actor2.expect_measured_samples_unchanged();  // markers are float in every encoding

  // /health and /metrics per subject.
  ASSERT_EQ(health["subjects"].size(), 2u);
  EXPECT_EQ(health["subjects"][1]["name"], "Actor2");
  EXPECT_TRUE(health["subjects"][1]["present"].get<bool>());
  EXPECT_GT(health["subjects"][1]["frames"]["published"].get<long>(), 0);
  EXPECT_GE(health["subjects"][0]["subscribers"].get<int>(), 0);
}

TEST(DaemonSubjects, AHelloNamingAnUnknownSubjectIsRefusedWithAStatusAndClosed) {
  StageServer server(stage().actor1, stage().actor2, 1.0);
  Daemon daemon(stage_config(server.port()));
  daemon.start();
  const Received refused = subscribe(daemon, hello_v2("Nobody"), [](const Received&) { return false; });
  EXPECT_TRUE(refused.closed_by_daemon);
  EXPECT_TRUE(refused.mesh_infos.empty());
  EXPECT_TRUE(refused.frames.empty());
  ASSERT_EQ(refused.statuses.size(), 1u);
  EXPECT_EQ(refused.statuses[0].state, subscriber::SourceStateCode::Refused);
  EXPECT_EQ(refused.statuses[0].detail, "no subject \"Nobody\" here (this daemon serves \"Actor1\", \"Actor2\")");
  EXPECT_EQ(daemon.subject(0).metrics().subscribers_refused.load(), 1u);

  // The same over WebSocket: one Status, refused, then the daemon closes the connection.
  asio::io_context io;
  websocket::stream<beast::tcp_stream> ws(io);
  beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(daemon.http_port())));
  ws.handshake("127.0.0.1", "/stream");
  ws.binary(true);
  ws.write(asio::buffer(subscriber::encode_hello(hello_v2("Nobody"))));
  beast::flat_buffer message;
  ws.read(message);
  const std::span<const unsigned char> bytes(static_cast<const unsigned char*>(message.cdata().data()), message.size());
  const subscriber::MessageHeader header = subscriber::decode_header(bytes);
  ASSERT_EQ(header.type, subscriber::MessageType::Status);
  EXPECT_EQ(header.version, subscriber::kVersion2);
  EXPECT_EQ(subscriber::decode_status(bytes.subspan(subscriber::kHeaderBytes), header.version).state, subscriber::SourceStateCode::Refused);
  boost::system::error_code ec;
  beast::flat_buffer rest;
  ws.read(rest, ec);
  EXPECT_TRUE(ec) << "the connection stayed open";

  // An encoding the daemon does not know is said in a Status, and float positions come, from
  // the subject named.
  subscriber::Hello unknown_encoding = hello_v2("Actor2");
  unknown_encoding.encoding = 7;
  const Received asked = subscribe(daemon, unknown_encoding, frames_at_least(3));
  ASSERT_EQ(asked.mesh_infos.size(), 1u);
  EXPECT_EQ(asked.mesh_infos[0].subject, "Actor2");
  EXPECT_EQ(asked.mesh_infos[0].encoding, subscriber::Encoding::Float);
  bool said = false;
  for (const subscriber::Status& s : asked.statuses) said = said || s.detail.find("encoding 7 is not one this daemon serves") == 0;
  EXPECT_TRUE(said);
  EXPECT_EQ(asked.frames.size(), 3u);
  daemon.stop();
}

TEST(DaemonSubjects, ASubjectLeavesAndReturnsWhileTheOtherStreamsOn) {
  StageServer server(stage().actor1, stage().actor2_leaving, 2.0);
  Daemon daemon(stage_config(server.port()));
  daemon.start();
  // Actor2's subscriber, until it has seen Actor2 leave (absent after frames came) and come back
  // with frames again.
  auto left_and_returned = [](const Received& r) {
    size_t left = r.statuses.size();
    for (size_t i = 0; i < r.statuses.size() && left == r.statuses.size(); ++i)
      if (!r.statuses[i].subject_present && r.statuses[i].state == subscriber::SourceStateCode::Streaming && r.frames_before_status[i] > 0)
        left = i;
    for (size_t i = left + 1; i < r.statuses.size(); ++i)
      if (r.statuses[i].subject_present && r.frames.size() > r.frames_before_status[i] + 20) return true;
    return false;
  };
  Received actor1;
  std::atomic<bool> actor2_done{false};
  std::thread other([&] { actor1 = subscribe(daemon, hello_v2("Actor1"), [&](const Received&) { return actor2_done.load(); }); });
  const Received actor2 = subscribe(daemon, hello_v2("Actor2"), left_and_returned);
  actor2_done = true;
  other.join();
  daemon.stop();

  // Actor2's frames: none from the stretch it was off the stage, and some after it.
  bool after = false;
  for (const subscriber::Frame& f : actor2.frames) {
    const int index = (static_cast<int>(f.info.frame_number) - stage().actor1.first_frame) % kFrames;
    EXPECT_TRUE(index < kOffStageFrom || index >= kOffStageTo) << "a frame while Actor2 was off the stage: " << f.info.frame_number;
    after = after || index >= kOffStageTo;
  }
  EXPECT_TRUE(after);
  // The Status that said it had gone (after frames had come).
  size_t gone = 0;
  while (gone < actor2.statuses.size() && (actor2.statuses[gone].subject_present || actor2.frames_before_status[gone] == 0)) ++gone;
  ASSERT_LT(gone, actor2.statuses.size());
  const subscriber::Status* absent = &actor2.statuses[gone];
  EXPECT_NE(absent->detail.find("subject Actor2 absent, waiting for it: the stream has no subject \"Actor2\" (it has \"Actor1\")"),
            std::string::npos)
      << absent->detail;
  // Actor1 streamed on meanwhile, without a gap in its numbers beyond what the pipeline dropped.
  ASSERT_GT(actor1.frames.size(), 100u);
  for (size_t i = 1; i < actor1.frames.size(); ++i) {
    const subscriber::FrameInfo& a = actor1.frames[i - 1].info;
    const subscriber::FrameInfo& b = actor1.frames[i].info;
    ASSERT_EQ(b.frame_number - a.frame_number, 1 + (b.pipeline_dropped - a.pipeline_dropped) + (b.subscriber_dropped - a.subscriber_dropped))
        << "frame " << b.frame_number;
  }
}

TEST(DaemonSubjects, AStalledSubscriberOfOneSubjectDoesNotSlowTheOthersSubscriber) {
  StageServer server(stage().actor1, stage().actor2, 4.0);
  DaemonConfig config = stage_config(server.port());
  config.subscriber_queue_frames = 256;  // the healthy subscriber never needs more
  config.max_frame_wait_ms = 1000;       // nor waits that long on a busy machine
  Daemon daemon(config);
  daemon.start_serving();
  // Actor1's subscriber asks for markers and never reads.
  asio::io_context io;
  tcp::socket stalled = test::stalled_subscriber(io, daemon.sub_port(), subscriber::encode_hello(hello_v2("Actor1")));
  wait_until([&] { return !daemon.subject(0).hub().wanted_encodings().empty(); });
  daemon.start_source();
  auto stalled_dropped = [&] {
    uint64_t most = 0;
    for (const SubscriberMetrics& s : daemon.subject(0).hub().subscriber_metrics()) most = std::max(most, s.dropped);
    return most;
  };
  // Actor2's subscriber runs until Actor1's stalled one has lost a good number of frames.
  const Received healthy = subscribe(daemon, hello_v2("Actor2"), [&](const Received&) { return stalled_dropped() >= 500; });
  const uint64_t source_skipped = daemon.source_metrics().source_frames_skipped.load();
  daemon.stop();
  ASSERT_GT(healthy.frames.size(), 500u);
  // In order (the replay numbers frames across loops), and a number missing only where the
  // pipeline dropped a frame (or the source never delivered one). A frame's count of the
  // pipeline's drops may already hold frames newer than it that gave way while it was being
  // processed (they are older than the next one published), so with missing(x) the numbers
  // missing between the first frame and x, and dropped(x) its count since the first frame:
  //   dropped(a) <= missing(b), b the frame after a (nothing dropped that was not missed), and
  //   missing(a) <= dropped(a) + missing(second frame) + source skips (nothing missed that was
  //   not dropped; the first frame's own count may hold drops of frames up to the second).
  const std::vector<subscriber::Frame>& frames = healthy.frames;
  auto missing = [&](size_t i) { return frames[i].info.frame_number - frames[0].info.frame_number - i; };
  auto dropped = [&](size_t i) { return frames[i].info.pipeline_dropped - frames[0].info.pipeline_dropped; };
  for (size_t i = 1; i < frames.size(); ++i) {
    const subscriber::FrameInfo& a = frames[i - 1].info;
    const subscriber::FrameInfo& b = frames[i].info;
    EXPECT_EQ(b.subscriber_dropped, 0u) << "frame " << b.frame_number;
    ASSERT_GT(b.frame_number, a.frame_number);
    ASSERT_LE(dropped(i - 1), missing(i)) << "frame " << b.frame_number;
    ASSERT_LE(missing(i - 1), dropped(i - 1) + missing(1) + source_skipped) << "frame " << a.frame_number;
  }
}

}  // namespace
}  // namespace skinstream::server
