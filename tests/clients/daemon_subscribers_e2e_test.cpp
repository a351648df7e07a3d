// Who may subscribe to the real skinstreamd, for how long, and what it costs, over loopback
// sockets with peers written here: the subscriber limits in all and per address, the allow-list
// of networks, the shared token (in Hello and on the WebSocket URL), the write-stall timeout, and
// MeshInfo sent again only when what it describes changes. Several subscriber hosts are played
// from 127.0.0.x addresses.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/daemon_process.h"
#include "support/loopback_peer.h"
#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::connect_loopback;
using test::eventually;

struct Message {
  subscriber::MessageHeader header;
  std::vector<unsigned char> payload;
};

// A subscriber written in the test: it says Hello (or nothing) and reads when told to.
class RawSubscriber {
 public:
  explicit RawSubscriber(int port, const std::string& from = "", int receive_buffer_bytes = 0)
      : fd_(connect_loopback(port, from, receive_buffer_bytes)) {}
  ~RawSubscriber() { hang_up(); }
  RawSubscriber(const RawSubscriber&) = delete;
  RawSubscriber& operator=(const RawSubscriber&) = delete;
  void hang_up() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }
  bool connected() const { return fd_ >= 0; }
  bool say(const subscriber::Hello& hello) {
    const std::vector<unsigned char> bytes = subscriber::encode_hello(hello);
    return send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
  }
  // The next whole message, or nullopt when the connection closed or nothing came within `limit`.
  std::optional<Message> next(std::chrono::seconds limit = std::chrono::seconds(20)) {
    unsigned char header[subscriber::kHeaderBytes];
    if (!read_exactly(header, sizeof header, limit)) return std::nullopt;
    Message message{subscriber::decode_header(header), {}};
    message.payload.resize(message.header.payload_bytes);
    if (!read_exactly(message.payload.data(), message.payload.size(), limit)) return std::nullopt;
    return message;
  }
  // Reads whole messages until a Frame begins, then only that Frame's header, and stops there: the
  // daemon's write of that frame stays under way (true), holding its pooled frame.
  bool read_into_a_frame() {
    for (;;) {
      unsigned char header[subscriber::kHeaderBytes];
      if (!read_exactly(header, sizeof header, std::chrono::seconds(20))) return false;
      const subscriber::MessageHeader decoded = subscriber::decode_header(header);
      if (decoded.type == subscriber::MessageType::Frame) return true;
      std::vector<unsigned char> skipped(decoded.payload_bytes);
      if (!read_exactly(skipped.data(), skipped.size(), std::chrono::seconds(20))) return false;
    }
  }
  // Reads until the daemon closes the connection (true) or `limit` passes (false).
  bool closed_by_daemon(std::chrono::seconds limit = std::chrono::seconds(20)) {
    unsigned char sink[65536];
    const auto end = std::chrono::steady_clock::now() + limit;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      pollfd readable{fd_, POLLIN, 0};
      if (left.count() <= 0 || poll(&readable, 1, static_cast<int>(left.count())) <= 0) return false;
      if (recv(fd_, sink, sizeof sink, 0) <= 0) return true;
    }
  }

 private:
  bool read_exactly(unsigned char* out, size_t size, std::chrono::seconds limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    for (size_t got = 0; got < size;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      pollfd readable{fd_, POLLIN, 0};
      if (left.count() <= 0 || poll(&readable, 1, static_cast<int>(left.count())) <= 0) return false;
      const ssize_t n = recv(fd_, out + got, size - got, 0);
      if (n <= 0) return false;
      got += static_cast<size_t>(n);
    }
    return true;
  }
  int fd_;
};

subscriber::Hello hello_v2(std::string token = "") {
  subscriber::Hello hello;
  hello.version = subscriber::kVersion2;
  hello.wants = subscriber::kWantMarkers;
  hello.token = std::move(token);
  return hello;
}

// The subscriber is served: its first message is MeshInfo.
::testing::AssertionResult served(RawSubscriber& peer) {
  const std::optional<Message> first = peer.next();
  if (!first) return ::testing::AssertionFailure() << "no message, or the connection closed";
  if (first->header.type != subscriber::MessageType::MeshInfo)
    return ::testing::AssertionFailure() << "first message is " << subscriber::to_string(first->header.type);
  return ::testing::AssertionSuccess();
}

// The subscriber says `hello` and is served.
::testing::AssertionResult served(RawSubscriber& peer, const subscriber::Hello& hello) {
  if (!peer.say(hello)) return ::testing::AssertionFailure() << "the Hello could not be sent";
  return served(peer);
}

// The subscriber is told it is refused (a Status whose detail holds `why`), then closed.
::testing::AssertionResult refused(RawSubscriber& peer, const std::string& why) {
  const std::optional<Message> first = peer.next();
  if (!first) return ::testing::AssertionFailure() << "no Status before the connection closed";
  if (first->header.type != subscriber::MessageType::Status)
    return ::testing::AssertionFailure() << "first message is " << subscriber::to_string(first->header.type);
  const subscriber::Status status = subscriber::decode_status(first->payload, first->header.version);
  const auto expected = first->header.version >= subscriber::kVersion2 ? subscriber::SourceStateCode::Refused
                                                                        : subscriber::SourceStateCode::Disconnected;
  if (status.state != expected || status.detail.find(why) == std::string::npos)
    return ::testing::AssertionFailure() << "Status state " << static_cast<int>(status.state) << ": " << status.detail;
  if (!peer.closed_by_daemon()) return ::testing::AssertionFailure() << "not closed after the refusal";
  return ::testing::AssertionSuccess();
}

// The status line of the reply to a WebSocket upgrade of `target`.
std::string upgrade_reply(int http_port, const std::string& target, const std::string& from = "") {
  const std::string request = "GET " + target +
                              " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                              "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
  // A successful upgrade keeps the connection open: the reply is what came within the limit.
  return test::http_exchange_within(http_port, request, std::chrono::seconds(3), from);
}

long resident_kb(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

nlohmann::json health_of(int http_port) {
  const std::string reply = test::http_get_within(http_port, "/health", std::chrono::seconds(10));
  const size_t body = reply.find("\r\n\r\n");
  if (body == std::string::npos) return {};
  return nlohmann::json::parse(reply.substr(body + 4), nullptr, false);
}

// The daemon replaying the demo body (53,500 vertices, frames of 640 kB) in a loop, with these
// config keys on top of the defaults.
std::unique_ptr<test::DaemonProcess> start_demo_daemon(const nlohmann::json& keys = nlohmann::json::object()) {
  static int configs = 0;
  const std::string demo = SKINSTREAM_DEMO_DIR;
  const std::string config = test::scratch_path("demo_" + std::to_string(getpid()) + "_" + std::to_string(configs++) + ".json");
  std::ofstream(config) << keys.dump();
  return std::make_unique<test::DaemonProcess>("--config " + config + " --subject " + demo + "/subject.sksubj --replay " +
                                                                demo + "/live.c3d --loop");
}

class DaemonAdmission : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    subject_ = test::scratch_path("admission_subject_" + std::to_string(getpid()) + ".sks");
    const test::ProgramRun built = test::run_program(std::string(SKINSTREAM_CLI) + " build-subject --capture " +
                                                     test::source_path("replay_data/cmu/85_02.c3d") + " --out " + subject_);
    ASSERT_EQ(built.exit_code, 0) << built.output;
  }
  static void TearDownTestSuite() { std::remove(subject_.c_str()); }

  // The daemon replaying a take in a loop, with these config keys on top of the defaults.
  std::unique_ptr<test::DaemonProcess> start(const nlohmann::json& keys) {
    const std::string config = test::scratch_path("admission_" + std::to_string(getpid()) + "_" + std::to_string(configs_++) + ".json");
    std::ofstream(config) << keys.dump();
    return std::make_unique<test::DaemonProcess>("--config " + config + " --subject " + subject_ + " --replay " +
                                                                  test::source_path("replay_data/cmu/85_12.c3d") + " --loop");
  }
  static inline std::string subject_;
  static inline int configs_ = 0;
};

TEST_F(DaemonAdmission, SubscribersBeyondTheLimitsAreToldWhyAndClosed) {
  auto daemon = start({{"max_subscribers", 3}, {"max_subscribers_per_address", 2}});
  ASSERT_GT(daemon->sub_port, 0);
  RawSubscriber first(daemon->sub_port, "127.0.0.1"), second(daemon->sub_port, "127.0.0.1");
  ASSERT_TRUE(first.say(hello_v2()) && second.say(hello_v2()));
  EXPECT_TRUE(served(first));
  EXPECT_TRUE(served(second));

  // A third from the same address; the same from another address is served.
  RawSubscriber third(daemon->sub_port, "127.0.0.1");
  ASSERT_TRUE(third.say(hello_v2()));
  EXPECT_TRUE(refused(third, "at most 2 from one address (max_subscribers_per_address)"));
  RawSubscriber other_host(daemon->sub_port, "127.0.0.2");
  ASSERT_TRUE(other_host.say(hello_v2()));
  EXPECT_TRUE(served(other_host));

  // Three in all: a fourth host is refused, on either port; a version 1 subscriber hears it as
  // "disconnected" with the same reason, after its Hello timeout if it says nothing.
  RawSubscriber fourth_host(daemon->sub_port, "127.0.0.3");
  EXPECT_TRUE(refused(fourth_host, "at most 3 (max_subscribers)"));
  const std::string reply = upgrade_reply(daemon->http_port, "/stream", "127.0.0.3");
  EXPECT_EQ(reply.rfind("HTTP/1.1 503", 0), 0u) << reply;
  EXPECT_NE(reply.find("too many subscribers: this daemon serves at most 3 (max_subscribers)"), std::string::npos) << reply;

  const nlohmann::json limits = health_of(daemon->http_port)["subscriber_limits"];
  EXPECT_EQ(limits["max_subscribers"], 3) << limits;
  EXPECT_EQ(limits["max_subscribers_per_address"], 2) << limits;
  EXPECT_EQ(limits["admitted"], 3) << limits;
  EXPECT_EQ(limits["refused_limit"], 3) << limits;

  // A place comes free when a subscriber leaves.
  first.hang_up();
  EXPECT_TRUE(eventually([&] { return health_of(daemon->http_port)["subscriber_limits"]["admitted"] == 2; }));
  RawSubscriber later(daemon->sub_port, "127.0.0.3");
  ASSERT_TRUE(later.say(hello_v2()));
  EXPECT_TRUE(served(later));
  EXPECT_EQ(daemon->stop(), 0) << daemon->log();
}

TEST_F(DaemonAdmission, OnlyAllowedNetworksMaySubscribe) {
  auto daemon = start({{"allow_subscribers", {"127.0.0.2", "10.0.0.0/8", "::1/128"}}});
  ASSERT_GT(daemon->sub_port, 0);
  RawSubscriber outside(daemon->sub_port, "127.0.0.1");
  ASSERT_TRUE(outside.say(hello_v2()));
  EXPECT_TRUE(refused(outside, "address 127.0.0.1 is not in this daemon's allow_subscribers networks"));
  RawSubscriber inside(daemon->sub_port, "127.0.0.2");
  ASSERT_TRUE(inside.say(hello_v2()));
  EXPECT_TRUE(served(inside));

  const std::string reply = upgrade_reply(daemon->http_port, "/stream", "127.0.0.1");
  EXPECT_EQ(reply.rfind("HTTP/1.1 403", 0), 0u) << reply;
  EXPECT_EQ(upgrade_reply(daemon->http_port, "/stream", "127.0.0.2").rfind("HTTP/1.1 101", 0), 0u);
  // /health is not a subscription: it answers everyone.
  const nlohmann::json limits = health_of(daemon->http_port)["subscriber_limits"];
  EXPECT_EQ(limits["allow_subscribers"], nlohmann::json({"127.0.0.2/32", "10.0.0.0/8", "::1/128"})) << limits;
  EXPECT_EQ(limits["refused_not_allowed"], 2) << limits;
  EXPECT_EQ(daemon->stop(), 0) << daemon->log();
}

TEST_F(DaemonAdmission, ASharedTokenIsAskedInHelloOrOnTheUrl) {
  auto daemon = start({{"subscriber_token", "stage-7/east"}});
  ASSERT_GT(daemon->sub_port, 0);
  RawSubscriber with_token(daemon->sub_port);
  ASSERT_TRUE(with_token.say(hello_v2("stage-7/east")));
  EXPECT_TRUE(served(with_token));
  RawSubscriber wrong(daemon->sub_port);
  ASSERT_TRUE(wrong.say(hello_v2("stage-7/west")));
  EXPECT_TRUE(refused(wrong, "wrong token"));
  RawSubscriber version1(daemon->sub_port);  // Hello version 1 has no token
  ASSERT_TRUE(version1.say(subscriber::Hello{subscriber::kWantMarkers}));
  EXPECT_TRUE(refused(version1, "this daemon asks for a token"));

  EXPECT_EQ(upgrade_reply(daemon->http_port, "/stream?token=stage-7%2Feast").rfind("HTTP/1.1 101", 0), 0u);
  const std::string reply = upgrade_reply(daemon->http_port, "/stream?token=stage-7");
  EXPECT_EQ(reply.rfind("HTTP/1.1 403", 0), 0u) << reply;
  EXPECT_NE(reply.find("wrong token"), std::string::npos) << reply;
  const nlohmann::json limits = health_of(daemon->http_port)["subscriber_limits"];
  EXPECT_EQ(limits["token_required"], true) << limits;
  EXPECT_EQ(limits["refused_token"], 3) << limits;
  EXPECT_EQ(daemon->log().find("stage-7/east"), std::string::npos) << "the token was logged";
  EXPECT_EQ(daemon->stop(), 0) << daemon->log();
}

// Idle connections that never give the token, 64 from each of four addresses, once held all 256
// places, and a subscriber with the right token was refused. They now hold places of their own,
// at most 4 from one address; the rest are refused as they connect (counted), and a token holder
// is served on either port. (Both Hello timeouts are long here: the idle ones stay.)
TEST_F(DaemonAdmission, IdleConnectionsWithoutTheTokenCannotKeepATokenHolderOut) {
  auto daemon = start({{"subscriber_token", "stage-7/east"}, {"hello_timeout_ms", 60000}, {"unauthenticated_hello_timeout_ms", 60000}});
  ASSERT_GT(daemon->sub_port, 0);
  std::vector<std::unique_ptr<RawSubscriber>> idle;
  for (int host = 2; host <= 5; ++host)
    for (int i = 0; i < 64; ++i) {
      idle.push_back(std::make_unique<RawSubscriber>(daemon->sub_port, "127.0.0." + std::to_string(host)));
      ASSERT_TRUE(idle.back()->connected());
    }
  EXPECT_TRUE(eventually([&] { return health_of(daemon->http_port)["subscriber_limits"]["refused_unauthenticated"] == 240; }))
      << health_of(daemon->http_port)["subscriber_limits"];
  RawSubscriber holder(daemon->sub_port, "127.0.0.6");
  EXPECT_TRUE(served(holder, hello_v2("stage-7/east")));
  EXPECT_EQ(upgrade_reply(daemon->http_port, "/stream?token=stage-7%2Feast", "127.0.0.6").rfind("HTTP/1.1 101", 0), 0u);
  const nlohmann::json limits = health_of(daemon->http_port)["subscriber_limits"];
  EXPECT_EQ(limits["unauthenticated"], 16) << limits;
  EXPECT_EQ(limits["refused_limit"], 0) << limits;
  EXPECT_GE(limits["admitted"], 1) << limits;
  // One of the idle ones that holds a place gives the token late: it becomes a subscriber.
  EXPECT_TRUE(served(*idle.front(), hello_v2("stage-7/east")));
  EXPECT_EQ(daemon->stop(), 0) << daemon->log();
}

// A connection that is to give the token and says nothing is refused after the short Hello
// timeout for those (it waited the subscribers' 2 s, holding a subscriber's place).
TEST_F(DaemonAdmission, AConnectionThatNeverGivesTheTokenIsClosedSoon) {
  auto daemon = start({{"subscriber_token", "stage-7/east"}, {"unauthenticated_hello_timeout_ms", 300}});
  ASSERT_GT(daemon->sub_port, 0);
  RawSubscriber silent(daemon->sub_port, "127.0.0.7");
  EXPECT_TRUE(refused(silent, "no Hello with the token within 300 ms"));
  EXPECT_TRUE(eventually([&] { return health_of(daemon->http_port)["subscriber_limits"]["unauthenticated"] == 0; }));
  EXPECT_EQ(health_of(daemon->http_port)["subscriber_limits"]["admitted"], 0);
  EXPECT_EQ(daemon->stop(), 0) << daemon->log();
}

// A subscriber that says Hello and never reads: once its socket buffers are full (a frame of the
// demo body is 640 kB), its write makes no progress, and after subscriber_write_stall_ms it is
// closed and counted, while a subscriber that reads goes on.
TEST(DaemonDemoSubscribers, ASubscriberWhoseWriteStallsIsDropped) {
  const auto started = start_demo_daemon({{"subscriber_write_stall_ms", 500}});
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber stalled(daemon.sub_port, "", 4096);
  ASSERT_TRUE(stalled.say(subscriber::Hello{}));
  ASSERT_TRUE(eventually([&] { return health_of(daemon.http_port)["subscriber_limits"]["dropped_write_stall"] == 1; }))
      << health_of(daemon.http_port).dump();
  EXPECT_TRUE(stalled.closed_by_daemon());
  EXPECT_TRUE(eventually([&] { return health_of(daemon.http_port)["subscribers"] == 0; }));
  EXPECT_NE(daemon.log().find("made no progress"), std::string::npos) << daemon.log();
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

// 60 subscribers from 8 hosts that stop reading in the middle of a frame each hold that frame
// (the daemon grows the pool for them off the pipeline thread: /health's promise of 0 frame
// buffers made there holds); once they leave, the pool shrinks back to its high water mark (the
// most frames in use at once since the last Status tick) plus the frames it keeps free, and RSS
// comes down within a generous bound.
TEST(DaemonDemoSubscribers, ThePoolShrinksBackToItsHighWaterMarkAfterStalledSubscribersLeave) {
  const auto started = start_demo_daemon();
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber good(daemon.sub_port);
  ASSERT_TRUE(served(good, subscriber::Hello{0}));
  const nlohmann::json before = health_of(daemon.http_port)["frame_pool"];
  ASSERT_TRUE(before.is_object()) << health_of(daemon.http_port).dump();
  const long rss_before = resident_kb(daemon.pid());
  nlohmann::json during;
  {
    std::vector<std::unique_ptr<RawSubscriber>> stalled;
    for (int i = 0; i < 60; ++i) {
      stalled.push_back(std::make_unique<RawSubscriber>(daemon.sub_port, "127.0.0." + std::to_string(2 + i % 8), 4096));
      ASSERT_TRUE(stalled.back()->say(subscriber::Hello{0}));
      ASSERT_TRUE(stalled.back()->read_into_a_frame());
      for (int frames = 0; frames < 2; ++frames) ASSERT_TRUE(good.next());  // the next one stalls in a later frame
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (std::chrono::steady_clock::now() < until) ASSERT_TRUE(good.next());
    during = health_of(daemon.http_port);
    std::printf("pool before %s, with 60 stalled %s; RSS %ld kB before, %ld kB with them\n", before.dump().c_str(),
                during["frame_pool"].dump().c_str(), rss_before, resident_kb(daemon.pid()));
    EXPECT_GE(during["frame_pool"]["in_use"].get<int>(), 30) << "the stalled subscribers hold their frames";
    EXPECT_GT(during["frame_pool"]["frames"].get<int>(), before["frames"].get<int>());
  }
  // Gone: within a few Status ticks the pool is its high water mark (the good subscriber's
  // frames and those queued for it) plus the frames kept free.
  nlohmann::json after;
  auto pool_back = [&] {
    for (int i = 0; i < 10; ++i) good.next(std::chrono::seconds(1));  // keep reading
    after = health_of(daemon.http_port);
    const nlohmann::json& pool = after["frame_pool"];
    return pool["frames"].get<int>() == pool["in_use_high_water"].get<int>() + pool["kept_free"].get<int>() &&
           pool["in_use_high_water"].get<int>() < 30;
  };
  EXPECT_TRUE(eventually(pool_back)) << after["frame_pool"].dump();
  EXPECT_EQ(after["frame_buffers_allocated_by_pipeline"], 0) << after.dump();
  // Within 10% (the soak's bound): 60 held frames are 38 MB, about 70% of the daemon's RSS. The
  // pool counts its frames gone before its thread has freed them (deleted outside its lock, then
  // handed back to the system): measured, RSS sampled once right after /health said 9 frames was
  // 69-94 MB in 8 of 26 runs (the test failed on it), and 58 MB 250 ms later in each run sampled
  // again. So RSS gets a moment to follow; the bound is the same.
  long rss_after = 0;
  EXPECT_TRUE(eventually(
      [&] {
        rss_after = resident_kb(daemon.pid());
        return rss_after < rss_before + rss_before / 10;
      },
      std::chrono::seconds(5)))
      << "the stalled subscribers' memory did not come back: RSS " << rss_after << " kB";
  std::printf("pool after they left %s; RSS %ld kB\n", after["frame_pool"].dump().c_str(), rss_after);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

// Subscribers that each ask for another format once (as a Hello flood cycling through the flags
// does) and leave: every pooled frame gets a buffer of each format, and before the hold-off those
// stayed for good (the soak's first wave left RSS at +102%). Once nobody has wanted a format for
// the hold-off (10 s), its buffers are freed on the 1 Hz tick, never on the pipeline thread, and
// RSS comes back, while the good subscriber is served throughout.
TEST(DaemonDemoSubscribers, BuffersOfFormatsNobodyWantsAnyMoreAreFreed) {
  const auto started = start_demo_daemon();
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber good(daemon.sub_port);
  ASSERT_TRUE(served(good, subscriber::Hello{0}));
  const long rss_before = resident_kb(daemon.pid());
  const uint32_t formats[] = {subscriber::kFrameNormals, subscriber::kFrameNormals | subscriber::kFrameMarkers,
                              subscriber::kFrameNormals | subscriber::kFrameQuantised, subscriber::kFrameMarkers};
  for (const uint32_t flags : formats) {
    RawSubscriber once(daemon.sub_port);
    ASSERT_TRUE(served(once, subscriber::Hello{flags}));
    ASSERT_TRUE(once.next()) << "a frame in format " << flags;
    for (int frames = 0; frames < 4; ++frames) ASSERT_TRUE(good.next());
  }
  const long rss_with = resident_kb(daemon.pid());
  const nlohmann::json with = health_of(daemon.http_port);
  ASSERT_TRUE(with["frame_pool"].is_object()) << with.dump();
  const int pool_frames = with["frame_pool"]["frames"].get<int>();
  // Every frame the pool keeps (at least kept_free) held a buffer of each format; a frame the
  // 1 Hz trim frees takes its buffers with it, uncounted.
  const int kept = with["frame_pool"]["kept_free"].get<int>();
  // What the formats cost depends on how many pooled frames held their buffers (8-10 here: 13-37
  // MB): at least half of it must come back, to within the same of where RSS was before them.
  ASSERT_GT(rss_with - rss_before, 8 * 1024) << "the formats' buffers cost too little to tell their return";
  auto came_back = [&](long rss) { return rss < rss_before + (rss_with - rss_before) / 2; };
  nlohmann::json after;
  auto released = [&] {
    for (int i = 0; i < 10; ++i) good.next(std::chrono::seconds(1));  // keep reading
    after = health_of(daemon.http_port);
    return after["frame_buffers_released"].get<int>() >= 4 * kept && came_back(resident_kb(daemon.pid()));
  };
  EXPECT_TRUE(eventually(released, std::chrono::seconds(40))) << after.dump();
  EXPECT_EQ(after["frame_buffers_allocated_by_pipeline"], 0) << after.dump();
  const long rss_after = resident_kb(daemon.pid());
  std::printf("RSS %ld kB before, %ld kB with 4 more formats, %ld kB once nobody wanted them (%d pooled frames)\n", rss_before,
              rss_with, rss_after, pool_frames);
  EXPECT_TRUE(came_back(rss_after)) << "the formats' buffers did not come back";
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

// 300 subscribers from 8 hosts connect at once, say Hello and never read (the first 255 are
// admitted, the rest refused by max_subscribers). The daemon writes each its 1.35 MB MeshInfo
// and frames until their sockets hold subscriber_unsent_kb unsent: before that limit, filling
// their 2.6-4 MB send buffers took the publish threads from the good subscriber for 0.4-0.6 s.
// The good subscriber, reading all along, loses no frame: the daemon drops none of its frames
// (its count in every Frame stays 0), its frame numbers skip only what the pipeline itself
// dropped, and the pipeline makes no frame buffer on its own thread. Frames may wait 200 ms
// for it (max_frame_wait_ms) rather than 25, so that the machine's other load (tests run two at
// a time on two cores) is not counted; the starving this guards against held its writes
// longer than that.
TEST(DaemonDemoSubscribers, ThreeHundredStalledSubscribersConnectingAtOnceDoNotStarveAGoodOne) {
  const auto started = start_demo_daemon({{"max_frame_wait_ms", 200}});
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber good(daemon.sub_port);
  ASSERT_TRUE(served(good, subscriber::Hello{0}));
  ASSERT_TRUE(good.next());  // a first Frame or Status: it is streaming
  const uint64_t pipeline_dropped_before = health_of(daemon.http_port)["frames"]["dropped"].get<uint64_t>();

  std::atomic<bool> stop{false};
  uint64_t frames = 0, skipped = 0, daemon_dropped = 0;
  bool lost_connection = false;
  std::thread reader([&] {
    uint32_t previous = 0;
    while (!stop.load()) {
      const std::optional<Message> message = good.next(std::chrono::seconds(5));
      if (!message) {
        lost_connection = true;
        return;
      }
      if (message->header.type != subscriber::MessageType::Frame) continue;
      const subscriber::FrameInfo info = subscriber::decode_frame_info(message->payload, message->header.version);
      daemon_dropped = std::max<uint64_t>(daemon_dropped, info.subscriber_dropped);
      // The replay loops: its frame numbers start again (a step back), otherwise they count up.
      if (frames > 0 && info.frame_number > previous) skipped += info.frame_number - previous - 1;
      previous = info.frame_number;
      ++frames;
    }
  });
  {
    std::vector<std::unique_ptr<RawSubscriber>> stalled;
    for (int i = 0; i < 300; ++i) stalled.push_back(std::make_unique<RawSubscriber>(daemon.sub_port, "127.0.0." + std::to_string(2 + i % 8)));
    for (auto& s : stalled) EXPECT_TRUE(s->say(subscriber::Hello{0}));
    std::this_thread::sleep_for(std::chrono::seconds(4));  // they fill their sockets and stall; the good one reads on
    const nlohmann::json during = health_of(daemon.http_port);
    EXPECT_EQ(during["subscribers"], 256) << during["subscriber_limits"].dump();
    EXPECT_EQ(during["subscriber_limits"]["refused_limit"], 45);
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  stop = true;
  reader.join();
  const nlohmann::json after = health_of(daemon.http_port);
  const uint64_t pipeline_dropped = after["frames"]["dropped"].get<uint64_t>() - pipeline_dropped_before;
  std::printf("good subscriber: %lu frames, %lu numbers skipped, dropped for it %lu; the pipeline dropped %lu; pool %s\n",
              static_cast<unsigned long>(frames), static_cast<unsigned long>(skipped), static_cast<unsigned long>(daemon_dropped),
              static_cast<unsigned long>(pipeline_dropped), after["frame_pool"].dump().c_str());
  EXPECT_FALSE(lost_connection);
  EXPECT_GE(frames, 300u) << "5 s at 120 Hz";
  EXPECT_EQ(daemon_dropped, 0u);
  EXPECT_LE(skipped, pipeline_dropped);
  EXPECT_EQ(after["frame_buffers_allocated_by_pipeline"], 0) << after.dump();
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

// MeshInfo (1.35 MB for the demo body) comes again after a Hello only when what it describes
// changes: not for normals or markers, but for positions no longer wanted.
TEST(DaemonDemoSubscribers, MeshInfoIsSentAgainOnlyWhenWhatItDescribesChanges) {
  const auto started = start_demo_daemon();
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber peer(daemon.sub_port);
  // MeshInfo messages (and their vertex counts) until `frames` Frames have come after it.
  auto mesh_infos_within = [&](int frames) {
    std::vector<uint32_t> vertex_counts;
    for (int seen = 0; seen < frames;) {
      const std::optional<Message> m = peer.next();
      if (!m) break;
      if (m->header.type == subscriber::MessageType::MeshInfo)
        vertex_counts.push_back(subscriber::decode_mesh_info(m->payload, m->header.version).vertex_count);
      seen += m->header.type == subscriber::MessageType::Frame;
    }
    return vertex_counts;
  };
  const uint32_t vertices = health_of(daemon.http_port)["subject"]["vertices"];
  ASSERT_GT(vertices, 0u);
  ASSERT_TRUE(peer.say(subscriber::Hello{0}));
  EXPECT_EQ(mesh_infos_within(30), std::vector<uint32_t>{vertices});
  ASSERT_TRUE(peer.say(subscriber::Hello{subscriber::kWantNormals | subscriber::kWantMarkers}));
  EXPECT_EQ(mesh_infos_within(60), std::vector<uint32_t>{}) << "MeshInfo sent again for normals and markers";
  ASSERT_TRUE(peer.say(subscriber::Hello{subscriber::kWantMarkers | subscriber::kWantNoMesh}));
  EXPECT_EQ(mesh_infos_within(60), std::vector<uint32_t>{0});
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

// Render nodes joining together: their MeshInfo (1.3 MB each for the demo body) goes out paced
// at subscriber_join_mbit for all of them together, while a watcher already in keeps its frames.
TEST(DaemonDemoSubscribers, JoinersAreSentTheirMeshInfoAtTheJoinRateWhileAWatcherKeepsItsFrames) {
  const int mbit = 40;  // 5 MB/s
  const auto started = start_demo_daemon({{"subscriber_join_mbit", mbit}});
  test::DaemonProcess& daemon = *started;
  ASSERT_GT(daemon.sub_port, 0);
  RawSubscriber watcher(daemon.sub_port);
  ASSERT_TRUE(served(watcher, subscriber::Hello{subscriber::kWantMarkers | subscriber::kWantNoMesh}));
  std::atomic<bool> stop{false};
  std::atomic<int> watcher_frames{0};
  std::thread watching([&] {
    while (!stop.load())
      if (const std::optional<Message> m = watcher.next(std::chrono::seconds(2));
          m && m->header.type == subscriber::MessageType::Frame)
        ++watcher_frames;
  });
  ASSERT_TRUE(eventually([&] { return watcher_frames.load() > 10; }));

  constexpr int kJoiners = 4;
  std::vector<std::unique_ptr<RawSubscriber>> joiners;
  for (int j = 0; j < kJoiners; ++j) joiners.push_back(std::make_unique<RawSubscriber>(daemon.sub_port));
  const auto joined = std::chrono::steady_clock::now();
  const int frames_before = watcher_frames.load();
  for (auto& joiner : joiners) ASSERT_TRUE(joiner->say(subscriber::Hello{0}));
  // Each joiner reads its MeshInfo and its first frame's header, in turn: the others' bytes wait
  // in their sockets meanwhile, which the pacer does not see.
  size_t mesh_info_bytes = 0;
  for (auto& joiner : joiners) {
    const std::optional<Message> first = joiner->next();
    ASSERT_TRUE(first && first->header.type == subscriber::MessageType::MeshInfo);
    mesh_info_bytes += subscriber::kHeaderBytes + first->payload.size();
    ASSERT_TRUE(joiner->read_into_a_frame());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - joined).count();
  const int watched = watcher_frames.load() - frames_before;
  stop = true;
  watching.join();
  for (auto& joiner : joiners) joiner->hang_up();

  // All but the first piece waited their turn at the rate.
  const double rate = mbit * 1e6 / 8;
  const double paced = static_cast<double>(mesh_info_bytes - 64 * 1024) / rate;
  EXPECT_GT(seconds, 0.9 * paced) << mesh_info_bytes << " bytes";
  EXPECT_LT(seconds, 3 * paced + 2) << mesh_info_bytes << " bytes";
  const nlohmann::json pacing = health_of(daemon.http_port)["join_pacing"];
  EXPECT_EQ(pacing["mbit"], mbit) << pacing.dump();
  EXPECT_GE(pacing["bytes"].get<double>(), static_cast<double>(mesh_info_bytes)) << pacing.dump();
  EXPECT_GT(pacing["pieces_delayed"].get<int>(), 0) << pacing.dump();
  // The watcher's frames went on meanwhile (120 a second; loaded test machines are slower).
  EXPECT_GT(watched, 60 * seconds) << watched << " frames in " << seconds << " s";
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

}  // namespace
}  // namespace skinstream
