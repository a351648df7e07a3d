// The client library's multicast receiver against the real skinstreamd between network
// namespaces on one bridge (multicast does not loop back on these machines): the daemon in one,
// replaying the demo subject and sending its parameters to a group; receivers in the others,
// each fetching the Model over TCP and evaluating the group's frames, compared with the daemon's
// float vertex buffer of the same frames; and one receiver that loses a tenth of its datagrams.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <regex>
#include <thread>

#include "skinstream/client.h"
#include "support/bridged_namespaces.h"
#include "support/client_frames.h"
#include "server/client/daemon_process.h"
#include "support/test_data.h"
#include "support/program_run.h"
#include "support/received_vertices.h"

namespace skinstream {
namespace {

using test::compare;
using test::Difference;
using test::Received;

// A frame's vertices and when the daemon published it: the replay loops, so a frame number comes
// back; the float and parameter messages of one publication carry the same publish time.
struct Stamped {
  Received vertices;
  int64_t publish_time_ns = 0;
};

void keep_stamped(const client::Frame& frame, Stamped& kept) {
  test::keep_vertices(frame, kept.vertices);
  kept.publish_time_ns = frame.publish_time_ns;
}

// compare() over the frames both received from the same publication.
Difference compare_same(const std::map<uint32_t, Stamped>& reference, const std::map<uint32_t, Stamped>& other) {
  std::map<uint32_t, Received> truth, received;
  for (const auto& [number, kept] : other) {
    const auto it = reference.find(number);
    if (it == reference.end() || it->second.publish_time_ns != kept.publish_time_ns) continue;
    truth[number] = it->second.vertices;
    received[number] = kept.vertices;
  }
  return compare(truth, received);
}

constexpr const char* kGroup = "239.255.77.1";
constexpr uint16_t kGroupPort = 9577;
constexpr int kDaemonHost = 0, kReferenceHost = 1, kClean = 2, kLossy = 4;  // hosts kClean..kLossy-1 lose nothing
constexpr int kHosts = 5;

class MulticastDemo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    skip_reason_ = test::BridgedNamespaces::unavailable_reason();
    if (!skip_reason_.empty()) return;
    lan_ = std::make_unique<test::BridgedNamespaces>(kHosts);
    const std::string demo = SKINSTREAM_DEMO_DIR;
    // A fifth of real time, as the TCP test: the float reference takes every frame on this shared machine.
    server::DaemonLaunch launch;
    launch.program = SKINSTREAMD;
    launch.arguments = "--subject " + demo + "/subject.sksubj --replay " + demo + "/live.c3d --loop --speed 0.2 --multicast " + kGroup + ":" +
                       std::to_string(kGroupPort) + " --multicast-interface " + lan_->address(kDaemonHost);
    launch.exec_prefix = lan_->exec_prefix(kDaemonHost);
    launch.bind = "0.0.0.0";  // the receivers reach it over the bridge
    launch.files_stem = test::scratch_path("multicast_daemon_" + std::to_string(getpid()));
    try {
      daemon_ = std::make_unique<server::DaemonProcess>(launch);
    } catch (const std::exception& e) {
      startup_error_ = e.what();
    }
  }
  static void TearDownTestSuite() {
    if (daemon_) {
      EXPECT_EQ(daemon_->stop(), 0) << daemon_->log();
    }
    daemon_.reset();
    lan_.reset();  // removes the namespaces, the veth pairs and the bridge, whatever happened above
  }
  void SetUp() override {
    if (!skip_reason_.empty()) GTEST_SKIP() << skip_reason_;
    ASSERT_TRUE(daemon_) << startup_error_;
  }

  static client::Options options_on(int host) {
    client::Options o;
    o.host = lan_->address(kDaemonHost);
    o.port = static_cast<uint16_t>(daemon_->sub_port());
    o.connect_timeout = std::chrono::seconds(10);
    o.multicast = {kGroup, kGroupPort, lan_->address(host), 0, std::chrono::milliseconds(50)};
    return o;
  }

  // The daemon's float vertex buffer, over TCP, on the reference host, until `stop` or `count` frames.
  static std::map<uint32_t, Stamped> reference(int count) {
    lan_->enter(kReferenceHost);
    client::Options o;
    o.host = lan_->address(kDaemonHost);
    o.port = static_cast<uint16_t>(daemon_->sub_port());
    o.encoding = client::Encoding::Float;
    client::Subscriber sub(o);
    return test::receive_frames<Stamped>(sub, count, keep_stamped);
  }

  static inline std::string skip_reason_;
  static inline std::unique_ptr<test::BridgedNamespaces> lan_;
  static inline std::unique_ptr<server::DaemonProcess> daemon_;
  static inline std::string startup_error_;
};

TEST_F(MulticastDemo, EveryReceiverEvaluatesTheDaemonsVertices) {
  constexpr int kFrames = 40;
  std::map<uint32_t, Stamped> truth;
  std::vector<std::map<uint32_t, Stamped>> received(kLossy - kClean);
  std::vector<client::MulticastStats> stats(received.size());
  std::vector<std::string> errors(received.size());
  std::vector<std::thread> threads;
  for (int r = 0; r < static_cast<int>(received.size()); ++r)
    threads.emplace_back([&, r] {
      try {
        lan_->enter(kClean + r);
        client::Subscriber sub(options_on(kClean + r));
        received[r] = test::receive_frames<Stamped>(sub, kFrames, keep_stamped);
        stats[r] = sub.multicast_stats();
      } catch (const std::exception& e) {
        errors[r] = e.what();
      }
    });
  threads.emplace_back([&] { truth = reference(kFrames + 20); });
  for (std::thread& t : threads) t.join();
  ASSERT_GE(truth.size(), size_t{kFrames});
  for (size_t r = 0; r < received.size(); ++r) {
    ASSERT_EQ(errors[r], "") << "receiver " << r;
    EXPECT_EQ(received[r].size(), size_t{kFrames}) << "receiver " << r;
    const Difference d = compare_same(truth, received[r]);
    // The same frames as the float subscriber: two threads joined at about the same time.
    EXPECT_GE(d.frames, kFrames / 2) << "receiver " << r;
    EXPECT_LE(d.position_mm, 0.01) << "receiver " << r;
    EXPECT_LE(d.normal_degrees, 0.01) << "receiver " << r;
    EXPECT_EQ(stats[r].datagrams_rejected + stats[r].messages_rejected, 0u) << stats[r].last_error;
    std::printf("receiver %zu: %d frames compared, largest difference %.3g mm %.3g deg; %llu datagrams, %llu frames, %llu lost\n", r,
                d.frames, d.position_mm, d.normal_degrees, static_cast<unsigned long long>(stats[r].datagrams),
                static_cast<unsigned long long>(stats[r].frames_completed), static_cast<unsigned long long>(stats[r].frames_lost));
  }
}

// A tenth of the datagrams to one receiver are dropped on their way in (nftables in its
// namespace; this kernel has no netem): it loses only frames one of whose datagrams was dropped,
// hands out no stale frame, and the frames it completes are still the daemon's.
TEST_F(MulticastDemo, ALossyReceiverLosesOnlyTheFramesItsDatagramsCarried) {
  if (test::run_program("nft --version").exit_code != 0) GTEST_SKIP() << "needs nftables' nft to drop datagrams (Debian: apt-get install nftables)";
  lan_->run_in(kLossy, "nft add table inet loss");
  lan_->run_in(kLossy, "nft add chain inet loss input '{ type filter hook input priority 0; }'");
  lan_->run_in(kLossy, "nft add rule inet loss input udp dport " + std::to_string(kGroupPort) + " numgen random mod 10 '<' 1 counter drop");
  constexpr auto kListen = std::chrono::seconds(5);
  std::map<uint32_t, Stamped> truth, received;
  client::MulticastStats stats;
  std::string error;
  double longest_wait_s = 0, stalest_s = 0;
  std::thread lossy([&] {
    try {
      lan_->enter(kLossy);
      client::Subscriber sub(options_on(kLossy));
      client::Frame frame;
      // The first frame, then kListen of the stream.
      while (!sub.next(frame, std::chrono::seconds(1))) {
      }
      auto last = std::chrono::steady_clock::now();
      const auto end = last + kListen;
      while (std::chrono::steady_clock::now() < end) {
        if (!sub.next(frame, std::chrono::milliseconds(200))) continue;
        const auto now = std::chrono::steady_clock::now();
        longest_wait_s = std::max(longest_wait_s, std::chrono::duration<double>(now - last).count());
        last = now;
        stalest_s = std::max(stalest_s, (frame.ready_time_ns - frame.publish_time_ns) * 1e-9);
        keep_stamped(frame, received[frame.frame_number]);
      }
      stats = sub.multicast_stats();
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  std::thread reference_thread([&] { truth = reference(40); });
  lossy.join();
  reference_thread.join();
  const std::string counters = lan_->run_in(kLossy, "nft list table inet loss");
  lan_->run_in(kLossy, "nft delete table inet loss");
  ASSERT_EQ(error, "");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(counters, match, std::regex("counter packets ([0-9]+)"))) << counters;
  const uint64_t dropped = std::stoull(match[1]);
  // About 24 frames a second of 6 datagrams: over 100 datagrams dropped in 5 s, about half the frames lost.
  EXPECT_GT(dropped, 20u);
  EXPECT_GT(stats.frames_lost, 0u);
  EXPECT_LE(stats.frames_lost, dropped);  // each dropped datagram costs at most its own frame
  EXPECT_GT(stats.frames_completed, 0u);
  // Never stalls: no frame it hands out is old. (The longest wait between frames is printed, not
  // asserted: the daemon itself pauses for seconds when this shared machine is loaded.)
  EXPECT_LT(stalest_s, 1.0);
  EXPECT_EQ(stats.datagrams_rejected + stats.messages_rejected, 0u) << stats.last_error;
  const Difference d = compare_same(truth, received);
  EXPECT_GE(d.frames, 3);
  EXPECT_LE(d.position_mm, 0.01);
  std::printf("lossy receiver: %llu datagrams dropped on the way, %llu frames completed, %llu lost (%llu incomplete), longest wait "
              "%.3f s, stalest frame %.3f s; %d frames compared, largest difference %.3g mm\n",
              static_cast<unsigned long long>(dropped), static_cast<unsigned long long>(stats.frames_completed),
              static_cast<unsigned long long>(stats.frames_lost), static_cast<unsigned long long>(stats.frames_incomplete), longest_wait_s,
              stalest_s, d.frames, d.position_mm);
}

}  // namespace
}  // namespace skinstream

namespace skinstream {
namespace {

// Anyone on the LAN can send to the group: datagrams that break the protocol, from another
// host, are counted by the receiver, which goes on with the daemon's frames.
TEST_F(MulticastDemo, BadDatagramsOnTheGroupAreCountedAndTheStreamGoesOn) {
  std::atomic<bool> receiving{true};
  std::thread vandal([&] {
    lan_->enter(kClean + 1);
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    in_addr interface{};
    inet_pton(AF_INET, lan_->address(kClean + 1).c_str(), &interface);
    setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &interface, sizeof interface);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    inet_pton(AF_INET, kGroup, &to.sin_addr);
    to.sin_port = htons(kGroupPort);
    // Foreign bytes; a header whose fragment is too short; one over 1,400 bytes; another stream's.
    std::vector<std::vector<unsigned char>> bad = {{1, 2, 3}};
    // A datagram header as the spec lays it out: magic SKSM, version 1, reserved, stream, model,
    // sequence, fragment index and count, message bytes.
    auto header = [](uint32_t stream, uint16_t count, uint32_t message_bytes) {
      std::vector<unsigned char> h(28);
      const uint32_t magic = 0x4D534B53, model = 1, sequence = 5;
      const uint16_t version = 1, reserved = 0, index = 0;
      unsigned char* p = h.data();
      for (const auto& [value, bytes] : std::initializer_list<std::pair<const void*, size_t>>{
               {&magic, 4}, {&version, 2}, {&reserved, 2}, {&stream, 4}, {&model, 4}, {&sequence, 4}, {&index, 2}, {&count, 2}, {&message_bytes, 4}}) {
        std::memcpy(p, value, bytes);
        p += bytes;
      }
      return h;
    };
    bad.push_back(header(0, 2, 2000));  // fragment 0 of 1,000 bytes, with none
    bad.push_back(std::vector<unsigned char>(1401, 0));
    std::vector<unsigned char> other_stream = header(7, 1, 10);
    other_stream.resize(other_stream.size() + 10);
    bad.push_back(other_stream);
    while (receiving.load())
      for (const auto& d : bad) {
        sendto(fd, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    close(fd);
  });
  std::map<uint32_t, Received> received;
  client::MulticastStats stats;
  std::string error;
  std::thread receiver([&] {
    try {
      lan_->enter(kClean);
      client::Subscriber sub(options_on(kClean));
      received = test::receive_frames<Received>(sub, 30, test::keep_vertices);
      stats = sub.multicast_stats();
    } catch (const std::exception& e) {
      error = e.what();
    }
    receiving.store(false);
  });
  receiver.join();
  vandal.join();
  ASSERT_EQ(error, "");
  EXPECT_EQ(received.size(), 30u);
  EXPECT_GT(stats.datagrams_rejected, 10u);
  EXPECT_GT(stats.datagrams_other_stream, 3u);
  EXPECT_EQ(stats.frames_lost, 0u);
  EXPECT_NE(stats.last_error.find("bad datagram"), std::string::npos) << stats.last_error;
  EXPECT_EQ(stats.last_error.find('\n'), std::string::npos) << stats.last_error;
  std::printf("%llu bad datagrams rejected (last: %s), %llu of another stream; %zu frames\n",
              static_cast<unsigned long long>(stats.datagrams_rejected), stats.last_error.c_str(),
              static_cast<unsigned long long>(stats.datagrams_other_stream), received.size());
}

}  // namespace
}  // namespace skinstream
