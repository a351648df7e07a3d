#pragma once
// Puts the multicast datagrams of one stream (protocol/multicast_datagram.h) back together into
// whole Frame messages, as they arrive, in any order. A frame whose fragments did not all arrive
// within the window, or that a newer complete frame overtook, is given up and counted: a lost
// datagram costs at most the frame it belonged to, and nothing ever waits for it. The buffers
// are made once, so taking a datagram allocates nothing (a bad one throws).

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "protocol/multicast_datagram.h"

namespace skinstream::subscriber {

class DatagramReassembler {
 public:
  using Clock = std::chrono::steady_clock;
  struct Options {
    uint32_t stream_id = 0;                                    // datagrams of other streams are counted and ignored
    std::chrono::nanoseconds window = std::chrono::milliseconds(50);  // a frame's fragments must all arrive within it
  };
  struct Stats {
    uint64_t datagrams = 0;           // taken, of this stream
    uint64_t frames_completed = 0;
    uint64_t frames_lost = 0;         // sequence numbers between completed frames that never completed
    uint64_t frames_incomplete = 0;   // of those, frames some of whose fragments arrived
    uint64_t datagrams_rejected = 0;  // broke the protocol (DecodeError)
    uint64_t datagrams_other_stream = 0;
    uint64_t datagrams_late = 0;       // of a frame already completed or given up
    uint64_t datagrams_duplicate = 0;
  };
  struct Message {
    std::span<const unsigned char> bytes;  // the whole Frame message; valid until the next add()
    DatagramHeader header;                 // of its last fragment (sequence, model id, ...)
  };

  explicit DatagramReassembler(const Options& options);

  // Takes one datagram (arrived at `now`). Returns the message it completes, if it does.
  // Throws DecodeError for a datagram that breaks the protocol or disagrees with the other
  // fragments of its frame (counted in datagrams_rejected); the frames in progress are kept.
  std::optional<Message> add(std::span<const unsigned char> datagram, Clock::time_point now);
  // Gives up the frames whose first fragment came more than the window before `now` (add()
  // does this too; call it when no datagram came for a while).
  void expire(Clock::time_point now);
  const Stats& stats() const { return stats_; }

 private:
  static constexpr int kSlots = 4;  // frames in progress at once (about 33 ms of a 120 Hz stream)
  struct Slot {
    bool used = false;
    DatagramHeader header;  // sequence, count, message size, model id of the frame
    uint64_t received = 0;  // bit i: fragment i arrived
    int fragments = 0;
    Clock::time_point first_arrival;
    std::vector<unsigned char> bytes;  // kMaxDatagramMessageBytes, made once
  };
  void give_up(Slot& slot);
  // The newest sequence completed or given up: fragments of it or older are late.
  bool is_late(uint32_t sequence) const;

  Options options_;
  std::array<Slot, kSlots> slots_;
  bool has_horizon_ = false;
  uint32_t horizon_ = 0;
  bool has_completed_ = false;
  uint32_t last_completed_ = 0;
  Stats stats_;
};

}  // namespace skinstream::subscriber
