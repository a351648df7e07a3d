// A replay server's client over a real loopback connection: the frame bound (the oldest waiting
// frame goes, replies never), what is counted, and closing (once, then forgotten by its list).
#include "server/replay/replay_client.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "server/replay/replay_client_list.h"

namespace skinstream::server {
namespace {

using std::chrono::milliseconds;

class TestClient : public ReplayClient {
 public:
  TestClient(tcp::socket socket, const ReplayClientContext& context, ReplayClientList<TestClient>& list)
      : ReplayClient(std::move(socket), context), list_(list) {}

  int closed_calls = 0;
  int writes_done = 0;

 protected:
  void after_write() override { ++writes_done; }
  void closed() override {
    ++closed_calls;
    list_.forget(this);
  }

 private:
  ReplayClientList<TestClient>& list_;
};

class ReplayClientTest : public ::testing::Test {
 protected:
  // One connected pair: `peer` is the client program's end, read synchronously by the test.
  std::shared_ptr<TestClient> connect(size_t max_queued_frames) {
    context_.max_queued_frames = max_queued_frames;
    tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    peer.connect(acceptor.local_endpoint());
    auto client = std::make_shared<TestClient>(acceptor.accept(), context_, list);
    ++clients_open;
    list.add(client);
    return client;
  }

  static ReplayClient::Packet packet(const std::string& text) {
    return std::make_shared<const std::vector<unsigned char>>(text.begin(), text.end());
  }

  void run_until_idle(const TestClient& client) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!client.idle() && std::chrono::steady_clock::now() < deadline) run_a_moment();
  }

  // The context stops whenever it runs out of work: restarted first.
  void run_a_moment() {
    io.restart();
    io.run_for(milliseconds(1));
  }

  std::string read_peer(size_t bytes) {
    std::string text(bytes, '\0');
    asio::read(peer, asio::buffer(text));
    return text;
  }

  asio::io_context io;
  tcp::socket peer{io};
  ReplayClientList<TestClient> list{io};
  RateLimitedLog log;
  std::atomic<uint64_t> clients_open{0}, bad_clients{0}, frame_packets_sent{0}, frames_dropped{0};

 private:
  ReplayClientContext context_{"test server", "test_bad_client", 0, log, clients_open, bad_clients,
                               frame_packets_sent, frames_dropped};
};

TEST_F(ReplayClientTest, AFrameBeyondTheBoundPushesOutTheOldestWaitingFrameAndRepliesStay) {
  const auto client = connect(2);
  client->enqueue(packet("A"), true);  // being written: never dropped
  client->enqueue(packet("r"), false);
  client->enqueue(packet("B"), true);
  client->enqueue(packet("C"), true);  // two frames waiting: the bound
  client->enqueue(packet("D"), true);  // B goes
  client->enqueue(packet("s"), false);
  client->enqueue(packet("E"), true);  // C goes
  EXPECT_EQ(frames_dropped.load(), 2u);
  EXPECT_EQ(client->replies_waiting(), 2u);
  EXPECT_FALSE(client->idle());
  run_until_idle(*client);
  EXPECT_EQ(read_peer(5), "ArDsE");
  EXPECT_EQ(frame_packets_sent.load(), 3u);
  EXPECT_EQ(client->replies_waiting(), 0u);
  EXPECT_EQ(client->writes_done, 5);
  EXPECT_TRUE(list.all_idle());
}

TEST_F(ReplayClientTest, ABoundOfNoneStillKeepsOneFrameWaiting) {
  const auto client = connect(0);
  client->enqueue(packet("A"), true);
  client->enqueue(packet("B"), true);
  client->enqueue(packet("C"), true);  // B goes
  EXPECT_EQ(frames_dropped.load(), 1u);
  run_until_idle(*client);
  EXPECT_EQ(read_peer(2), "AC");
  EXPECT_EQ(frame_packets_sent.load(), 2u);
}

TEST_F(ReplayClientTest, RejectingCountsClosesOnceAndTheListForgetsItAfterTheHandler) {
  const auto client = connect(4);
  client->enqueue(packet("A"), false);
  client->reject("a malformed packet");
  EXPECT_EQ(bad_clients.load(), 1u);
  EXPECT_EQ(clients_open.load(), 0u);
  EXPECT_FALSE(client->open());
  EXPECT_EQ(client->closed_calls, 1);
  EXPECT_EQ(client->replies_waiting(), 0u);
  client->close();
  client->enqueue(packet("B"), true);  // closed: nothing is queued
  EXPECT_EQ(client->closed_calls, 1);
  EXPECT_EQ(clients_open.load(), 0u);
  EXPECT_EQ(list.size(), 1u);  // posted: the client may be in its own handler
  io.poll();
  EXPECT_EQ(list.size(), 0u);
  EXPECT_EQ(frames_dropped.load(), 0u);
}

TEST_F(ReplayClientTest, AFailedWriteClosesTheClient) {
  const auto client = connect(4);
  peer.close();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (client->open() && std::chrono::steady_clock::now() < deadline) {
    client->enqueue(packet(std::string(64 * 1024, 'x')), false);
    run_a_moment();
  }
  EXPECT_FALSE(client->open());
  EXPECT_EQ(client->closed_calls, 1);
  EXPECT_EQ(clients_open.load(), 0u);
  EXPECT_EQ(bad_clients.load(), 0u);  // it left; it sent nothing malformed
}

TEST_F(ReplayClientTest, ClosingAllClosesEveryClientAndEmptiesTheList) {
  const auto first = connect(4);
  tcp::socket first_peer = std::move(peer);
  peer = tcp::socket(io);
  const auto second = connect(4);
  EXPECT_EQ(list.size(), 2u);
  list.close_all();
  EXPECT_EQ(list.size(), 0u);
  EXPECT_FALSE(first->open());
  EXPECT_FALSE(second->open());
  EXPECT_EQ(clients_open.load(), 0u);
  io.poll();  // the forgetting posted by each close finds nothing left
  EXPECT_EQ(list.size(), 0u);
}

}  // namespace
}  // namespace skinstream::server
