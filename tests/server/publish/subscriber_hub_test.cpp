// The hub with a real TCP subscriber on loopback: a subscriber whose stream key's buffers are
// not made yet waits for them without holding its io thread, receives nothing meanwhile, and
// starts with the first frame published after they are made.
#include "server/publish/subscriber_hub.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>
#include <vector>

#include "support/subscriber_client.h"
#include "server/publish/tcp_subscriber.h"

namespace skinstream::server {
namespace {

constexpr uint32_t kVertices = 3;

// A pooled frame of one triangle, encoded for `key`.
FrameRef frame_for(FramePool& pool, StreamKey key, uint32_t frame_number) {
  FrameRef ref = pool.acquire();
  EncodedFrame& frame = *ref.mutable_frame();
  subscriber::FrameInfo info;
  info.frame_number = frame_number;
  info.flags = stream_flags(key);
  info.vertex_count = kVertices;
  const std::vector<float> positions(3 * kVertices, 1.0f);
  frame.messages[key].resize(subscriber::frame_message_bytes(info.flags, kVertices, 0, stream_version(key)));
  subscriber::encode_frame(info, positions, {}, {}, {}, frame.messages[key], stream_version(key));
  frame.frame_number = frame_number;
  frame.published = std::chrono::steady_clock::now();
  frame.encoded.add(key);
  return ref;
}

template <typename Done>
bool wait_for(Done done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done() && std::chrono::steady_clock::now() < give_up) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  return done();
}

subscriber::MeshInfo one_triangle() {
  subscriber::MeshInfo info;
  info.vertex_count = kVertices;
  info.faces = {{0, 1, 2}};
  info.dominant_part.assign(kVertices, 0);
  return info;
}

// A hub whose preparer the test plays, and one real subscriber (Hello version 1, positions).
class SubscriberHubTest : public ::testing::Test {
 protected:
  using OnMessage = std::function<bool(subscriber::MessageType, std::span<const unsigned char>)>;

  // Accepts one subscriber into the hub and starts it; its messages go to `on_message` until
  // that returns false.
  void connect(OnMessage on_message) {
    io_thread_ = std::thread([&] { io_.run(); });
    acceptor_.async_accept([&](const boost::system::error_code& ec, tcp::socket socket) {
      ASSERT_FALSE(ec) << ec.message();
      auto session = std::make_shared<TcpSubscriber>(io_, hub, std::move(socket), "test");
      hub.add(session);
      session->start();
    });
    subscriber_thread_ = std::thread([on_message = std::move(on_message), port = acceptor_.local_endpoint().port()] {
      try {
        sub::SubscriberClient client("127.0.0.1", std::to_string(port), 0);
        client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) { return on_message(type, payload); });
      } catch (const std::exception& e) {
        ADD_FAILURE() << "subscriber: " << e.what();
      }
    });
  }
  void TearDown() override {
    asio::post(io_, [&] {
      hub.close_all();
      acceptor_.close();
    });
    guard_.reset();
    if (io_thread_.joinable()) io_thread_.join();
    if (subscriber_thread_.joinable()) subscriber_thread_.join();
  }
  bool io_thread_answers() {
    std::atomic<bool> ran{false};
    asio::post(io_, [&] { ran = true; });
    return wait_for([&] { return ran.load(); });
  }

  Metrics metrics;
  // Before the hub, so it outlives the sessions and the frames queued in them (TearDown joins
  // the io thread; the hub's sessions go with the hub).
  FramePool pool;
  SubscriberHub hub{metrics, HubOptions{}, one_triangle(), true};
  std::atomic<int> requests{0}, activations{0};
  std::atomic<StreamKey> requested{0};

 private:
  asio::io_context io_;
  asio::executor_work_guard<asio::io_context::executor_type> guard_{io_.get_executor()};
  tcp::acceptor acceptor_{io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  std::thread io_thread_, subscriber_thread_;
};

TEST_F(SubscriberHubTest, ASubscriberWaitsForItsKeysBuffersOffItsThreadAndStartsOnceTheyAreMade) {
  std::atomic<bool> made{false};
  hub.set_encoding_preparer({.ready = [&](StreamKey) { return made.load(); },
                             .request =
                                 [&](StreamKey key) {
                                   requested = key;
                                   ++requests;  // made later, by the test: the io thread must not wait for it
                                 },
                             .activated = [&](StreamKey) { ++activations; }});
  std::atomic<uint32_t> first_frame{0};
  std::atomic<int> frames{0};
  connect([&](subscriber::MessageType type, std::span<const unsigned char> payload) {
    if (type != subscriber::MessageType::Frame) return true;
    if (frames++ == 0) first_frame = subscriber::decode_frame_info(payload).frame_number;
    return false;
  });

  ASSERT_TRUE(wait_for([&] { return requests.load() == 1; })) << "the Hello asked for no buffers";
  EXPECT_EQ(hub.waiting_count(), 1u);
  EXPECT_EQ(hub.active_count(), 0u);
  EXPECT_TRUE(hub.wanted_encodings().empty()) << "a key without buffers is wanted: the pipeline would make them";
  EXPECT_EQ(activations.load(), 0);
  EXPECT_TRUE(io_thread_answers()) << "the io thread waits for the buffers";

  const StreamKey key = requested.load();
  hub.publish(frame_for(pool, key, 6));  // nobody receives it yet

  made = true;
  hub.encoding_prepared(key);
  EXPECT_EQ(hub.waiting_count(), 0u);
  EXPECT_EQ(hub.active_count(), 1u);
  EXPECT_TRUE(hub.wanted_encodings().has(key));
  EXPECT_EQ(activations.load(), 1);
  hub.publish(frame_for(pool, key, 7));
  ASSERT_TRUE(wait_for([&] { return frames.load() > 0; }));
  EXPECT_EQ(first_frame.load(), 7u) << "a frame published while the subscriber waited reached it";
}

TEST_F(SubscriberHubTest, ASubscriberThatLeavesWhileWaitingIsForgotten) {
  hub.set_encoding_preparer({.ready = [](StreamKey) { return false; },
                             .request =
                                 [&](StreamKey key) {
                                   requested = key;
                                   ++requests;
                                 },
                             .activated = [&](StreamKey) { ++activations; }});
  // Leaves as soon as its Hello has been answered (the MeshInfo).
  connect([](subscriber::MessageType type, std::span<const unsigned char>) { return type != subscriber::MessageType::MeshInfo; });
  ASSERT_TRUE(wait_for([&] { return requests.load() == 1; }));
  ASSERT_TRUE(wait_for([&] { return hub.subscriber_count() == 0; })) << "the session never left";
  EXPECT_EQ(hub.waiting_count(), 0u);
  hub.encoding_prepared(requested.load());  // the buffers come after it left: nobody starts
  EXPECT_EQ(hub.active_count(), 0u);
  EXPECT_EQ(activations.load(), 0);
}

}  // namespace
}  // namespace skinstream::server
