#include "protocol/subscriber/offer_reassembler.h"

#include <algorithm>
#include <cstring>

namespace skinstream::subscriber {
namespace {

bool same_offer(const DatagramHeader& a, const DatagramHeader& b) {
  return a.sequence == b.sequence && a.model_id == b.model_id && a.count == b.count &&
         a.message_bytes == b.message_bytes;
}

}  // namespace

OfferReassembler::OfferReassembler(const Options& options) : options_(options) {
  received_.resize((kMaxOfferFragments + 63) / 64);
}

void OfferReassembler::restart() { in_progress_ = false; }

std::optional<OfferReassembler::Offer> OfferReassembler::add(std::span<const unsigned char> datagram,
                                                             Clock::time_point now) {
  DatagramHeader h;
  try {
    h = decode_datagram_header(datagram);
    if (options_.authenticator) check_datagram_tag(*options_.authenticator, datagram, h);
    if (!h.offer) throw DecodeError("a datagram of a frame on the offer's port");
  } catch (const DecodeError&) {
    ++stats_.datagrams_rejected;
    throw;
  }
  if (h.stream_id != options_.stream_id) {
    ++stats_.datagrams_other_stream;
    return std::nullopt;
  }
  ++stats_.datagrams;
  if (!in_progress_ || !same_offer(h, offer_)) {
    if (in_progress_ && now - last_arrival_ < options_.stale_after) {
      ++stats_.datagrams_other_offer;
      return std::nullopt;
    }
    in_progress_ = true;
    offer_ = h;
    std::fill(received_.begin(), received_.end(), 0);
    fragments_ = 0;
    if (bytes_.size() < h.message_bytes) bytes_.resize(h.message_bytes);
    ++stats_.offers_begun;
  }
  last_arrival_ = now;
  uint64_t& word = received_[h.index / 64];
  const uint64_t bit = uint64_t{1} << (h.index % 64);
  if (word & bit) {
    ++stats_.datagrams_duplicate;
    return std::nullopt;
  }
  word |= bit;
  ++fragments_;
  const size_t fragment_size = fragment_bytes(h.message_bytes, h.count, h.index);
  std::memcpy(bytes_.data() + fragment_offset(h.message_bytes, h.count, h.index),
              datagram.data() + kDatagramHeaderBytes, fragment_size);
  if (fragments_ < h.count) return std::nullopt;
  in_progress_ = false;
  ++stats_.offers_completed;
  return Offer{std::span<const unsigned char>(bytes_).first(h.message_bytes), h};
}

}  // namespace skinstream::subscriber
