// What a receiver reads from a multicast group, from anyone on the LAN: the input cut into
// datagrams (each a 2-byte little-endian length, then that many bytes), fed 5 ms apart to one
// DatagramReassembler without a key and one with a key; for the one with the key, every other
// datagram is first signed with it (a tag appended, the flag set), so forged and signed ones
// mix. Only DecodeError may be thrown, with a one-line reason; every message completed has the
// size its datagrams said; the reassembler with the key completes only messages whose every
// datagram it saw signed, and counts every datagram it refused for its tag. The same datagrams go
// to an OfferReassembler, as to the offer's port: an offer it completes has its datagrams' size,
// and unpacking it (decode_offer) throws only DecodeError with one line.
#include <cstdlib>
#include <cstring>
#include <vector>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/datagram_authentication.h"
#include "protocol/subscriber/datagram_reassembler.h"
#include "protocol/subscriber/offer_content.h"
#include "protocol/subscriber/offer_reassembler.h"

namespace subscriber = skinstream::subscriber;

namespace {

const std::vector<unsigned char> kKey = {'f', 'u', 'z', 'z', ' ', 'm', 'u', 'l', 't', 'i', 'c', 'a', 's', 't', ' ', 'k', 'e', 'y'};

void add(subscriber::DatagramReassembler& reassembler, std::span<const unsigned char> datagram,
         subscriber::DatagramReassembler::Clock::time_point now) {
  try {
    const auto message = reassembler.add(datagram, now);
    if (message && message->bytes.size() != message->header.message_bytes) std::abort();
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
  }
}

void add(subscriber::OfferReassembler& reassembler, std::span<const unsigned char> datagram,
         subscriber::OfferReassembler::Clock::time_point now) {
  try {
    const auto offer = reassembler.add(datagram, now);
    if (!offer) return;
    if (offer->bytes.size() != offer->header.message_bytes) std::abort();
    subscriber::decode_offer(offer->bytes, offer->header.model_id);
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const auto authenticator = std::make_shared<const subscriber::DatagramAuthenticator>(kKey);
  subscriber::DatagramReassembler plain({.stream_id = 0, .window = std::chrono::milliseconds(20)});
  subscriber::DatagramReassembler keyed(
      {.stream_id = 0, .window = std::chrono::milliseconds(20), .max_ahead = 120, .resync_after = std::chrono::milliseconds(100), .authenticator = authenticator});
  subscriber::OfferReassembler offer({.stream_id = 0, .stale_after = std::chrono::milliseconds(20)});
  subscriber::DatagramReassembler::Clock::time_point now{};
  std::vector<unsigned char> signed_datagram;
  uint64_t unsigned_seen = 0;
  for (size_t at = 0, k = 0; at + 2 <= size; ++k) {
    uint16_t length;
    std::memcpy(&length, data + at, 2);
    at += 2;
    const size_t n = std::min<size_t>(length, size - at);
    const std::span<const unsigned char> datagram(data + at, n);
    at += n;
    now += std::chrono::milliseconds(5);
    add(plain, datagram, now);
    add(offer, datagram, now);
    if (k % 2 == 1 && n >= subscriber::kDatagramHeaderBytes) {
      // Signed as the daemon would: the flag set, the tag of header and fragment appended.
      signed_datagram.assign(datagram.begin(), datagram.end());
      signed_datagram[6] |= subscriber::kDatagramAuthenticated;
      const std::span<const unsigned char> parts[] = {signed_datagram};
      const subscriber::DatagramTag tag = authenticator->tag(parts);
      signed_datagram.insert(signed_datagram.end(), tag.begin(), tag.end());
      add(keyed, signed_datagram, now);
    } else {
      ++unsigned_seen;
      add(keyed, datagram, now);
    }
  }
  // Every datagram not signed here was refused (for its tag, or before it for its header).
  if (keyed.stats().datagrams_rejected < unsigned_seen) std::abort();
  return 0;
}
