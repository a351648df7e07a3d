#include "protocol/subscriber/datagram_reassembler.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace skinstream::subscriber {
namespace {

// Sequence numbers wrap at 2^32: a is after b when it is less than half the range ahead.
bool after(uint32_t a, uint32_t b) { return static_cast<int32_t>(a - b) > 0; }

}  // namespace

DatagramReassembler::DatagramReassembler(const Options& options) : options_(options) {
  for (Slot& slot : slots_) slot.bytes.resize(kMaxDatagramMessageBytes);
}

void DatagramReassembler::give_up(Slot& slot) {
  slot.used = false;
  ++stats_.frames_incomplete;
}

void DatagramReassembler::start(Slot& slot, const DatagramHeader& header, Clock::time_point now) {
  slot.used = true;
  slot.header = header;
  slot.received = 0;
  slot.fragments = 0;
  slot.first_arrival = now;
}

void DatagramReassembler::expire(Clock::time_point now) {
  for (Slot& slot : slots_)
    if (slot.used && now - slot.first_arrival > options_.window) give_up(slot);
}

bool DatagramReassembler::in_window(uint32_t sequence, Clock::time_point now) {
  if (!has_completed_) return true;
  const bool late = !after(sequence, last_completed_);
  if (!late && sequence - last_completed_ <= options_.max_ahead) return true;
  if (now - last_completed_at_ < options_.resync_after) {
    ++(late ? stats_.datagrams_late : stats_.datagrams_out_of_window);
    return false;
  }
  // Nothing completed for a while: whatever comes now is the stream.
  ++stats_.resyncs;
  has_completed_ = false;
  for (Slot& slot : slots_) slot.used = false;
  return true;
}

std::optional<DatagramReassembler::Message> DatagramReassembler::add(std::span<const unsigned char> datagram, Clock::time_point now) {
  DatagramHeader h;
  try {
    h = decode_datagram_header(datagram);
  } catch (const DecodeError&) {
    ++stats_.datagrams_rejected;
    throw;
  }
  const size_t fragment_size = datagram.size() - kDatagramHeaderBytes - (h.authenticated ? kDatagramTrailerBytes : 0);
  if (options_.authenticator) {
    try {
      check_datagram_tag(*options_.authenticator, datagram, h);
    } catch (const DecodeError&) {
      ++stats_.datagrams_rejected;
      ++stats_.datagrams_unauthenticated;
      throw;
    }
  }
  if (h.offer) {  // the offer has a port of its own
    ++stats_.datagrams_rejected;
    throw DecodeError("a datagram of the offer among the frames");
  }
  if (h.stream_id != options_.stream_id) {
    ++stats_.datagrams_other_stream;
    return std::nullopt;
  }
  ++stats_.datagrams;
  expire(now);
  if (!in_window(h.sequence, now)) return std::nullopt;
  // A fragment whose count, size or model differ from those of its sequence's other fragments
  // belongs to another frame of that sequence, put together beside it: one of the two is not the
  // sender's, and a copy of every real fragment with another model id once kept every real frame
  // from completing.
  Slot* slot = nullptr;
  for (Slot& s : slots_)
    if (s.used && s.header.sequence == h.sequence && s.header.count == h.count && s.header.message_bytes == h.message_bytes &&
        s.header.model_id == h.model_id)
      slot = &s;
  if (!slot) {
    // A free slot; else the frame furthest ahead gives way (the next one due is the one to keep;
    // of two of one sequence, the one with fewer fragments), unless this datagram is further
    // ahead still.
    for (Slot& s : slots_)
      if (!s.used) slot = &s;
    if (!slot) {
      Slot* furthest = &slots_[0];
      for (Slot& s : slots_)
        if (after(s.header.sequence, furthest->header.sequence) ||
            (s.header.sequence == furthest->header.sequence && s.fragments < furthest->fragments))
          furthest = &s;
      if (after(h.sequence, furthest->header.sequence)) {
        ++stats_.datagrams_no_slot;
        return std::nullopt;
      }
      give_up(*furthest);
      slot = furthest;
    }
    if (std::any_of(slots_.begin(), slots_.end(), [&](const Slot& s) { return s.used && s.header.sequence == h.sequence; }))
      ++stats_.frames_disputed;
    start(*slot, h, now);
  }
  const uint64_t bit = uint64_t{1} << h.index;
  if (slot->received & bit) {
    ++stats_.datagrams_duplicate;
    return std::nullopt;
  }
  slot->received |= bit;
  ++slot->fragments;
  std::memcpy(slot->bytes.data() + fragment_offset(h.message_bytes, h.count, h.index), datagram.data() + kDatagramHeaderBytes,
              fragment_size);
  if (slot->fragments < h.count) return std::nullopt;

  // Complete: the frames before it, and another of its sequence, are of no more use (the newest
  // frame wins).
  slot->used = false;
  for (Slot& s : slots_)
    if (s.used && !after(s.header.sequence, h.sequence)) give_up(s);
  if (has_completed_ && after(h.sequence, last_completed_)) stats_.frames_lost += h.sequence - last_completed_ - 1;
  has_completed_ = true;
  last_completed_ = h.sequence;
  last_completed_at_ = now;
  ++stats_.frames_completed;
  return Message{std::span<const unsigned char>(slot->bytes).first(h.message_bytes), h};
}

}  // namespace skinstream::subscriber
