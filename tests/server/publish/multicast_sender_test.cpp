// The multicast sender in front of the real subscriber hub: what it adds to the wanted stream
// keys, what it sends of a pooled frame (counted; sent through this host's loopback interface,
// where nobody listens), that the send allocates nothing, and one-line errors for bad options.
#include "server/publish/multicast_sender.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "server/publish/subscriber_hub.h"
#include "support/allocation_counter.h"
#include "support/fixture_bytes.h"

namespace skinstream::server {
namespace {

std::string error_of(const MulticastSenderOptions& options, SubscriberHub& hub) {
  try {
    MulticastSender sender(hub, options);
    return "";
  } catch (const std::runtime_error& e) {
    return e.what();
  }
}

TEST(MulticastSender, BadOptionsAreOneLineErrors) {
  Metrics metrics;
  SubscriberHub hub(metrics, {}, {}, true);
  EXPECT_NE(error_of({{"10.1.2.3", 9577}}, hub).find("is not an IPv4 multicast address"), std::string::npos);
  EXPECT_NE(error_of({{"stage", 9577}}, hub).find("is not an IPv4 multicast address"), std::string::npos);
  EXPECT_NE(error_of({{"239.255.77.1", 9577, "eth0"}}, hub).find("interface eth0 is not an IPv4 address"),
            std::string::npos);
  EXPECT_NE(error_of({{"239.255.77.1", 9577, "0.0.0.0", 300}}, hub).find("ttl must be 0-255"),
            std::string::npos);
  // An address that is not this host's.
  const std::string foreign = error_of({{"239.255.77.1", 9577, "192.0.2.77"}}, hub);
  EXPECT_NE(foreign.find("cannot set the interface"), std::string::npos) << foreign;
  EXPECT_EQ(foreign.find('\n'), std::string::npos);
}

TEST(MulticastSender, SendsEachFrameOfTheParameterStreamOnceWithoutAllocating) {
  Metrics metrics;
  SubscriberHub hub(metrics, {}, {}, true);
  MulticastSender sender(hub, {{"239.255.77.1", 9577, "127.0.0.1", 0}});
  EXPECT_TRUE(hub.wanted_encodings().empty());
  EXPECT_TRUE(sender.wanted_encodings().has(MulticastSender::sent_key()));  // the pipeline fits the parts for the group alone

  // The golden 1,928-byte parameter Frame message as the pipeline's pooled frame.
  const test::ByteVector message = test::fixture_bytes("multicast/frame.bin");
  FramePool pool(2);
  pool.prepare(MulticastSender::sent_key(), message.size());
  FrameRef frame = pool.acquire();
  ASSERT_FALSE(pool.size_message(*frame.mutable_frame(), MulticastSender::sent_key(), message.size()));
  std::copy(message.begin(), message.end(), frame.mutable_frame()->messages[MulticastSender::sent_key()].begin());
  frame.mutable_frame()->encoded.add(MulticastSender::sent_key());

  sender.publish(frame);  // no Model yet: nothing is sent
  EXPECT_EQ(sender.health()["datagrams_sent"], 0);
  const test::ByteVector model = test::fixture_bytes("subscriber/model.bin");
  sender.set_model(std::span(model).subspan(subscriber::kHeaderBytes));
  {
    const test::CountAllocations allocations;
    for (int i = 0; i < 10; ++i) sender.publish(frame);
    EXPECT_EQ(allocations.count(), 0u);
  }
  const nlohmann::json health = sender.health();
  EXPECT_EQ(health["frames_sent"], 10);
  EXPECT_EQ(health["datagrams_sent"], 20);  // 2 a frame
  EXPECT_EQ(health["bytes_sent"], 10 * (1928 + 2 * 28));
  EXPECT_EQ(health["model_id"], subscriber::model_id_of(std::span(model).subspan(subscriber::kHeaderBytes)));
  std::string text;
  sender.render_prometheus(text);
  EXPECT_NE(text.find("skinstream_multicast_datagrams_sent_total 20\n"), std::string::npos) << text;

  // A frame without the key (a later hand-over of the compressed encoding) sends nothing.
  FrameRef other = pool.acquire();
  sender.publish(other);
  EXPECT_EQ(sender.health()["frames_sent"], 10);
}

}  // namespace
}  // namespace skinstream::server
