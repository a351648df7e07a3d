#pragma once
// Puts the multicast datagrams of one stream (protocol/subscriber/multicast_datagram.h) back together into
// whole Frame messages, as they arrive, in any order. A frame whose fragments did not all arrive
// within the window, or that a newer complete frame overtook, is given up and counted: a lost
// datagram costs at most the frame it belonged to, and nothing ever waits for it. The buffers
// are made once, so taking a datagram allocates nothing (a bad one throws).
//
// Anyone on the LAN can send to the group, and copy the stream id, model id and sequence of a
// real datagram. With a key (Options::authenticator) only datagrams carrying its tag are taken.
// Without one, a forged or stale datagram costs at most resync_after (100 ms) of frames:
//   - only sequences in a window after the last completed frame (at most max_ahead ahead) are
//     taken while the stream flows; older ones are late, later ones out of the window, and both
//     are counted and ignored (one datagram of sequence + 1,200 once stopped every frame for
//     10 s, + 60,000 for the rest of the run);
//   - when no frame completed for resync_after, the next datagram starts the stream afresh,
//     whatever its sequence (the sender started again, or the network was away for long);
//   - with every slot in use, the frame furthest ahead gives way, not the next one due (about 360
//     forged first fragments a second once kept every real frame out), and a fragment whose
//     count, size or model id differ from its sequence's other fragments is put together apart
//     from them (a copy of every real fragment with another model id cannot spoil the real frame).

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "protocol/subscriber/datagram_authentication.h"
#include "protocol/subscriber/multicast_datagram.h"

namespace skinstream::subscriber {

class DatagramReassembler {
 public:
  using Clock = std::chrono::steady_clock;
  struct Options {
    uint32_t stream_id = 0;                                    // datagrams of other streams are counted and ignored
    std::chrono::nanoseconds window = std::chrono::milliseconds(50);  // a frame's fragments must all arrive within it
    uint32_t max_ahead = 120;                                  // frames after the last completed one (1 s at 120 Hz)
    std::chrono::nanoseconds resync_after = std::chrono::milliseconds(100);
    std::shared_ptr<const DatagramAuthenticator> authenticator{};  // set: datagrams must carry its tag
  };
  struct Stats {
    uint64_t datagrams = 0;           // taken, of this stream
    uint64_t frames_completed = 0;
    uint64_t frames_lost = 0;         // sequence numbers between completed frames that never completed
    uint64_t frames_incomplete = 0;   // of those, frames some of whose fragments arrived
    uint64_t datagrams_rejected = 0;  // broke the protocol (DecodeError), or without the key's tag
    uint64_t datagrams_other_stream = 0;
    uint64_t datagrams_late = 0;       // of a frame already completed or given up, or older
    uint64_t datagrams_duplicate = 0;
    uint64_t datagrams_out_of_window = 0;  // more than max_ahead after the last completed frame
    uint64_t datagrams_no_slot = 0;        // further ahead than every frame in progress, with none free
    uint64_t datagrams_unauthenticated = 0;  // of the rejected: no tag, or a wrong one
    uint64_t frames_disputed = 0;            // a second frame of one sequence begun (its count, size or model differ)
    uint64_t resyncs = 0;                    // the stream started afresh after resync_after without a frame
  };
  struct Message {
    std::span<const unsigned char> bytes;  // the whole Frame message; valid until the next add()
    DatagramHeader header;                 // of its last fragment (sequence, model id, ...)
  };

  explicit DatagramReassembler(const Options& options);

  // Takes one datagram (arrived at `now`). Returns the message it completes, if it does.
  // Throws DecodeError for a datagram that breaks the protocol or lacks the key's tag (counted
  // in datagrams_rejected); the frames in progress are kept.
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
  void start(Slot& slot, const DatagramHeader& header, Clock::time_point now);
  // Whether the datagram of `sequence` belongs to the stream as it flows (false: counted, ignored).
  bool in_window(uint32_t sequence, Clock::time_point now);

  Options options_;
  std::array<Slot, kSlots> slots_;
  bool has_completed_ = false;
  uint32_t last_completed_ = 0;
  Clock::time_point last_completed_at_{};
  Stats stats_;
};

}  // namespace skinstream::subscriber
