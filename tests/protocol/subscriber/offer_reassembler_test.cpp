#include "protocol/subscriber/offer_reassembler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "support/allocation_counter.h"
#include "support/fixture_bytes.h"

namespace skinstream::subscriber {
namespace {

using test::ByteVector;
using Clock = OfferReassembler::Clock;
using std::chrono::milliseconds;

// The datagrams of an offer of `bytes` bytes (each byte its offset mod 251, plus `salt`).
std::vector<ByteVector> offer_datagrams(uint32_t edition, size_t bytes = 100'000, uint32_t model = 9,
                                        uint32_t stream = 0, const DatagramAuthenticator* key = nullptr,
                                        unsigned char salt = 0) {
  const uint16_t count = fragment_count(bytes, key != nullptr, kMaxOfferFragments);
  std::vector<ByteVector> out;
  for (uint16_t i = 0; i < count; ++i) {
    ByteVector d(kDatagramHeaderBytes);
    encode_datagram_header(
        {stream, model, edition, i, count, static_cast<uint32_t>(bytes), key != nullptr, true},
        std::span<unsigned char, kDatagramHeaderBytes>(d.data(), kDatagramHeaderBytes));
    for (size_t b = fragment_offset(bytes, count, i);
         b < fragment_offset(bytes, count, i) + fragment_bytes(bytes, count, i); ++b)
      d.push_back(static_cast<unsigned char>(b % 251 + salt));
    if (key) {
      const std::span<const unsigned char> parts[] = {d};
      const DatagramTag tag = key->tag(parts);
      d.insert(d.end(), tag.begin(), tag.end());
    }
    out.push_back(std::move(d));
  }
  return out;
}

bool holds_offer(std::span<const unsigned char> offer, size_t bytes, unsigned char salt = 0) {
  if (offer.size() != bytes) return false;
  for (size_t b = 0; b < bytes; ++b)
    if (offer[b] != static_cast<unsigned char>(b % 251 + salt)) return false;
  return true;
}

// A receiver that joins halfway through a round, and loses datagrams, takes what it lacks from
// the next round: the offer is never asked for again.
TEST(OfferReassembler, AReceiverJoiningMidRoundAndLosingDatagramsCompletesFromTheNextRound) {
  OfferReassembler r({});
  const std::vector<ByteVector> round = offer_datagrams(4);
  ASSERT_EQ(round.size(), 73u);
  std::mt19937 random(7);
  std::optional<OfferReassembler::Offer> offer;
  Clock::time_point t{};
  // From fragment 40 on, every fourth datagram lost, then the next round whole.
  for (size_t pass = 0; pass < 2 && !offer; ++pass)
    for (size_t i = pass == 0 ? 40 : 0; i < round.size() && !offer; ++i) {
      t += milliseconds(1);
      if (pass == 0 && random() % 4 == 0) continue;
      offer = r.add(round[i], t);
    }
  ASSERT_TRUE(offer);
  EXPECT_TRUE(holds_offer(offer->bytes, 100'000));
  EXPECT_EQ(offer->header.sequence, 4u);
  EXPECT_EQ(offer->header.model_id, 9u);
  EXPECT_GT(r.stats().datagrams_duplicate, 10u);  // the second round's copies of what had come
  EXPECT_EQ(r.stats().offers_completed, 1u);
  EXPECT_EQ(r.stats().offers_begun, 1u);
}

TEST(OfferReassembler, FragmentsInAnyOrderMakeTheOffer) {
  OfferReassembler r({});
  std::vector<ByteVector> round = offer_datagrams(0, 40'000);
  std::shuffle(round.begin(), round.end(), std::mt19937(3));
  std::optional<OfferReassembler::Offer> offer;
  for (const ByteVector& d : round) {
    EXPECT_FALSE(offer) << "complete before its last fragment";
    offer = r.add(d, Clock::time_point{});
  }
  ASSERT_TRUE(offer);
  EXPECT_TRUE(holds_offer(offer->bytes, 40'000));
}

// The daemon moves on to a new edition (a swap, a new source rate): the receiver drops the old
// one once its datagrams stopped for stale_after, and takes the new one.
TEST(OfferReassembler, ANewEditionIsTakenOnceTheOldOnesDatagramsStopped) {
  OfferReassembler r({.stale_after = milliseconds(500)});
  const std::vector<ByteVector> old_edition = offer_datagrams(1, 50'000, 9),
                                next = offer_datagrams(2, 60'000, 10, 0, nullptr, 7);
  Clock::time_point t{};
  for (size_t i = 0; i < 10; ++i) EXPECT_FALSE(r.add(old_edition[i], t += milliseconds(1)));
  // Still fresh: the new edition's datagrams are counted and left.
  EXPECT_FALSE(r.add(next[0], t += milliseconds(100)));
  EXPECT_EQ(r.stats().datagrams_other_offer, 1u);
  t += milliseconds(600);
  std::optional<OfferReassembler::Offer> offer;
  for (const ByteVector& d : next) offer = r.add(d, t += milliseconds(1));
  ASSERT_TRUE(offer);
  EXPECT_EQ(offer->header.sequence, 2u);
  EXPECT_EQ(offer->header.model_id, 10u);
  EXPECT_TRUE(holds_offer(offer->bytes, 60'000, 7));
  EXPECT_EQ(r.stats().offers_begun, 2u);
}

// A forger's datagrams of another offer, mixed into the real rounds, cannot make the receiver
// drop the real one each time: it completes from the real rounds.
TEST(OfferReassembler, AnotherOffersDatagramsDoNotUndoTheOneInProgress) {
  OfferReassembler r({});
  const std::vector<ByteVector> real = offer_datagrams(5, 30'000, 9),
                                forged = offer_datagrams(5, 30'000, 666, 0, nullptr, 1);
  std::optional<OfferReassembler::Offer> offer;
  Clock::time_point t{};
  for (size_t i = 0; i < real.size() && !offer; ++i) {
    offer = r.add(real[i], t += milliseconds(1));
    if (!offer) EXPECT_FALSE(r.add(forged[i], t));
  }
  ASSERT_TRUE(offer);
  EXPECT_EQ(offer->header.model_id, 9u);
  EXPECT_TRUE(holds_offer(offer->bytes, 30'000));
  EXPECT_EQ(r.stats().datagrams_other_offer, real.size() - 1);
}

TEST(OfferReassembler, BadDatagramsAndFramesAreRefusedAndTheOfferGoesOn) {
  OfferReassembler r({.stream_id = 3});
  const std::vector<ByteVector> round = offer_datagrams(1, 5'000, 9, 3);
  EXPECT_FALSE(r.add(round[0], Clock::time_point{}));
  EXPECT_THROW(r.add(ByteVector(5, 0xEE), Clock::time_point{}), DecodeError);
  // A frame's datagram (no offer flag) on the offer's port.
  ByteVector frame = round[1];
  frame[6] = 0;
  try {
    r.add(frame, Clock::time_point{});
    ADD_FAILURE() << "a frame's datagram taken as the offer's";
  } catch (const DecodeError& e) {
    EXPECT_NE(std::string(e.what()).find("a datagram of a frame on the offer's port"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(r.add(offer_datagrams(1, 5'000, 9, 4)[1], Clock::time_point{}));  // another stream's
  EXPECT_EQ(r.stats().datagrams_other_stream, 1u);
  EXPECT_EQ(r.stats().datagrams_rejected, 2u);
  std::optional<OfferReassembler::Offer> offer;
  for (size_t i = 1; i < round.size(); ++i) offer = r.add(round[i], Clock::time_point{});
  ASSERT_TRUE(offer);
  EXPECT_TRUE(holds_offer(offer->bytes, 5'000));
}

TEST(OfferReassembler, WithAKeyOnlySignedDatagramsAreTaken) {
  const std::string secret = "offer key of sixteen bytes or more";
  auto key = std::make_shared<DatagramAuthenticator>(
      std::span(reinterpret_cast<const unsigned char*>(secret.data()), secret.size()));
  OfferReassembler r({.authenticator = key});
  const std::vector<ByteVector> signed_round = offer_datagrams(1, 20'000, 9, 0, key.get()),
                                unsigned_round = offer_datagrams(1, 20'000);
  EXPECT_THROW(r.add(unsigned_round[0], Clock::time_point{}), DecodeError);
  ByteVector tampered = signed_round[0];
  tampered[40] ^= 1;
  EXPECT_THROW(r.add(tampered, Clock::time_point{}), DecodeError);
  EXPECT_EQ(r.stats().datagrams_rejected, 2u);
  std::optional<OfferReassembler::Offer> offer;
  for (const ByteVector& d : signed_round) offer = r.add(d, Clock::time_point{});
  ASSERT_TRUE(offer);
  EXPECT_TRUE(holds_offer(offer->bytes, 20'000));
}

// An offer the receiver refused (its content was not a subject's) is forgotten: the next round
// makes it again.
TEST(OfferReassembler, ARestartTakesTheOfferAgainFromTheNextRound) {
  OfferReassembler r({});
  const std::vector<ByteVector> round = offer_datagrams(1, 9'000);
  std::optional<OfferReassembler::Offer> offer;
  for (const ByteVector& d : round) offer = r.add(d, Clock::time_point{});
  ASSERT_TRUE(offer);
  r.restart();
  offer.reset();
  for (const ByteVector& d : round) {
    EXPECT_FALSE(offer);
    offer = r.add(d, Clock::time_point{});
  }
  ASSERT_TRUE(offer);
  EXPECT_EQ(r.stats().offers_completed, 2u);
}

// Its buffer is made as an offer begins; the datagrams after that allocate nothing.
TEST(OfferReassembler, TakingDatagramsAllocatesNothingOnceTheOfferBegan) {
  OfferReassembler r({});
  const std::vector<ByteVector> round = offer_datagrams(1, 200'000);
  r.add(round[0], Clock::time_point{});
  const test::CountAllocations allocations;
  std::optional<OfferReassembler::Offer> offer;
  for (size_t i = 1; i < round.size(); ++i) offer = r.add(round[i], Clock::time_point{});
  EXPECT_EQ(allocations.count(), 0u);
  ASSERT_TRUE(offer);
}

}  // namespace
}  // namespace skinstream::subscriber
