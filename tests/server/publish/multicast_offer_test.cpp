// The multicast offer's sender: what it offers of the hub's packed messages, round after round at
// its rate (sent through this host's loopback interface, where nobody listens; receivers take it
// in tests/clients/cpp/multicast_test.cpp), a new edition when the messages change, nothing when
// there is nothing to offer or too much, and one-line errors for bad options.
#include "server/publish/multicast_offer.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <thread>

#include "protocol/subscriber/multicast_datagram.h"
#include "support/fixture_bytes.h"

namespace skinstream::server {
namespace {

ControlMessage fixture(const std::string& name) {
  return std::make_shared<const std::vector<unsigned char>>(test::fixture_bytes("subscriber/" + name));
}

// The golden packed MeshInfo and Model, as the hub gives them; swap() makes a new model.
struct OfferedContent {
  std::mutex mutex;
  MulticastOffer::Content content{fixture("packed_mesh_info_v2.bin"), fixture("packed_model.bin"),
                                  fixture("model.bin")};
  MulticastOffer::ContentSource source() {
    return [this] {
      std::lock_guard lock(mutex);
      return content;
    };
  }
};

MulticastSenderOptions loopback(double mbit) {
  MulticastSenderOptions o{{"239.255.77.1", 9577, "127.0.0.1", 0}};
  o.offer_mbit = mbit;
  return o;
}

bool wait_for(const std::function<bool()>& done) {
  for (auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
       std::chrono::steady_clock::now() < end;) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

TEST(MulticastOffer, OffersThePackedMessagesRoundAfterRoundNeverFasterThanItsRate) {
  OfferedContent offered;
  // 0.2 Mbit/s: a round of the golden offer (238 bytes) every 9.5 ms.
  MulticastOffer offer(loopback(0.2), offered.source());
  const auto start = std::chrono::steady_clock::now();
  offer.start();
  ASSERT_TRUE(wait_for([&] { return offer.health()["rounds"] >= 10; }));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  offer.stop();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json health = offer.health();
  EXPECT_EQ(health["port"], 9578);
  EXPECT_EQ(health["bytes"], 95 + 115);
  EXPECT_EQ(health["datagrams_per_round"], 1);
  EXPECT_EQ(health["edition"], 0);
  EXPECT_EQ(health["model_id"],
            subscriber::model_id_of(std::span(*offered.content.model).subspan(subscriber::kHeaderBytes)));
  EXPECT_EQ(health["datagrams_sent"], health["rounds"]);
  EXPECT_EQ(health["send_errors"], 0);
  // Paced: at most the rate's bytes over the time it ran, and a batch (one round here) more.
  const double bytes = health["bytes_sent"];
  EXPECT_LE(bytes, 0.2e6 / 8 * seconds + 238) << seconds << " s";
  std::string text;
  offer.render_prometheus(text);
  EXPECT_NE(
      text.find("skinstream_multicast_offer_rounds_total " + std::to_string(int(health["rounds"])) + "\n"),
      std::string::npos)
      << text;
}

TEST(MulticastOffer, ANewModelIsANewEdition) {
  OfferedContent offered;
  MulticastOffer offer(loopback(5), offered.source());
  offer.start();
  ASSERT_TRUE(wait_for([&] { return offer.health()["rounds"] >= 2; }));
  EXPECT_EQ(offer.health()["edition"], 0);
  {
    std::lock_guard lock(offered.mutex);  // the same bytes, as a swap to the same file brings them
    offered.content.packed_model = fixture("packed_model.bin");
  }
  EXPECT_TRUE(wait_for([&] { return offer.health()["edition"] == 1; }));
  {
    std::lock_guard lock(offered.mutex);  // a new source rate: a new packed MeshInfo
    offered.content.packed_mesh_info = fixture("packed_mesh_info_v2.bin");
  }
  EXPECT_TRUE(wait_for([&] { return offer.health()["edition"] == 2; }));
}

TEST(MulticastOffer, NothingToOfferOrTooMuchSendsNothing) {
  OfferedContent offered;
  offered.content = {};
  MulticastOffer none(loopback(50), offered.source());
  none.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  none.stop();
  EXPECT_EQ(none.health()["datagrams_sent"], 0);

  OfferedContent huge;
  huge.content.packed_mesh_info = std::make_shared<const std::vector<unsigned char>>(
      size_t{subscriber::kMaxOfferFragments} * subscriber::kMaxFragmentBytes, 0);
  MulticastOffer too_large(loopback(50), huge.source());
  too_large.start();
  ASSERT_TRUE(wait_for([&] { return too_large.health()["too_large"] >= 1; }));
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // past the offer thread's 1 s wait
  too_large.stop();
  EXPECT_EQ(too_large.health()["datagrams_sent"], 0);
  EXPECT_EQ(too_large.health()["too_large"], 1) << "made again though nothing changed";
}

std::string error_of(const MulticastSenderOptions& options) {
  OfferedContent offered;
  try {
    MulticastOffer offer(options, offered.source());
    return "";
  } catch (const std::runtime_error& e) {
    return e.what();
  }
}

TEST(MulticastOffer, BadOptionsAreOneLineErrors) {
  EXPECT_NE(error_of(loopback(0)).find("rate must be above 0"), std::string::npos);
  MulticastSenderOptions last_port = loopback(10);
  last_port.frames.port = 65535;
  EXPECT_NE(error_of(last_port).find("there is none"), std::string::npos);
  MulticastSenderOptions foreign = loopback(10);
  foreign.frames.interface_address = "192.0.2.77";
  const std::string error = error_of(foreign);
  EXPECT_NE(error.find("multicast 239.255.77.1:9578: cannot set the interface"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace skinstream::server
