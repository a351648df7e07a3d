#include "protocol/datagram_reassembler.h"

#include <cstring>
#include <string>

namespace skinstream::subscriber {
namespace {

// Sequence numbers wrap at 2^32: a is after b when it is less than half the range ahead.
bool after(uint32_t a, uint32_t b) { return static_cast<int32_t>(a - b) > 0; }
// A sender that starts again (a restarted daemon) counts from 0: a sequence this far behind
// the horizon starts the stream afresh instead of being late for ever.
constexpr uint32_t kRestartDistance = 1u << 16;

}  // namespace

DatagramReassembler::DatagramReassembler(const Options& options) : options_(options) {
  for (Slot& slot : slots_) slot.bytes.resize(kMaxDatagramMessageBytes);
}

bool DatagramReassembler::is_late(uint32_t sequence) const {
  return has_horizon_ && !after(sequence, horizon_) && horizon_ - sequence < kRestartDistance;
}

void DatagramReassembler::give_up(Slot& slot) {
  slot.used = false;
  ++stats_.frames_incomplete;
  if (!has_horizon_ || after(slot.header.sequence, horizon_)) horizon_ = slot.header.sequence;
  has_horizon_ = true;
}

void DatagramReassembler::expire(Clock::time_point now) {
  for (Slot& slot : slots_)
    if (slot.used && now - slot.first_arrival > options_.window) give_up(slot);
}

std::optional<DatagramReassembler::Message> DatagramReassembler::add(std::span<const unsigned char> datagram, Clock::time_point now) {
  DatagramHeader h;
  try {
    h = decode_datagram_header(datagram);
  } catch (const DecodeError&) {
    ++stats_.datagrams_rejected;
    throw;
  }
  if (h.stream_id != options_.stream_id) {
    ++stats_.datagrams_other_stream;
    return std::nullopt;
  }
  ++stats_.datagrams;
  expire(now);
  if (is_late(h.sequence)) {
    ++stats_.datagrams_late;
    return std::nullopt;
  }
  if (has_horizon_ && !after(h.sequence, horizon_)) {  // far behind: the sender started again
    for (Slot& slot : slots_) slot.used = false;
    has_horizon_ = has_completed_ = false;
  }
  Slot* slot = nullptr;
  for (Slot& s : slots_)
    if (s.used && s.header.sequence == h.sequence) slot = &s;
  if (slot && (slot->header.count != h.count || slot->header.message_bytes != h.message_bytes || slot->header.model_id != h.model_id)) {
    ++stats_.datagrams_rejected;
    throw DecodeError("fragment " + std::to_string(h.index) + " of frame " + std::to_string(h.sequence) +
                      " disagrees with the frame's other fragments (count, size or model)");
  }
  if (!slot) {
    // A free slot, else the oldest frame in progress gives way.
    for (Slot& s : slots_)
      if (!s.used) slot = &s;
    if (!slot) {
      slot = &slots_[0];
      for (Slot& s : slots_)
        if (after(slot->header.sequence, s.header.sequence)) slot = &s;
      give_up(*slot);
    }
    slot->used = true;
    slot->header = h;
    slot->received = 0;
    slot->fragments = 0;
    slot->first_arrival = now;
  }
  const uint64_t bit = uint64_t{1} << h.index;
  if (slot->received & bit) {
    ++stats_.datagrams_duplicate;
    return std::nullopt;
  }
  slot->received |= bit;
  ++slot->fragments;
  std::memcpy(slot->bytes.data() + fragment_offset(h.message_bytes, h.count, h.index), datagram.data() + kDatagramHeaderBytes,
              datagram.size() - kDatagramHeaderBytes);
  if (slot->fragments < h.count) return std::nullopt;

  // Complete: the frames before it are of no more use (the newest frame wins).
  slot->used = false;
  for (Slot& s : slots_)
    if (s.used && after(h.sequence, s.header.sequence)) give_up(s);
  if (has_completed_ && after(h.sequence, last_completed_)) stats_.frames_lost += h.sequence - last_completed_ - 1;
  has_completed_ = true;
  last_completed_ = h.sequence;
  if (!has_horizon_ || after(h.sequence, horizon_)) horizon_ = h.sequence;
  has_horizon_ = true;
  ++stats_.frames_completed;
  return Message{std::span<const unsigned char>(slot->bytes).first(h.message_bytes), h};
}

}  // namespace skinstream::subscriber
