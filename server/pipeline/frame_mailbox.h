#pragma once
// Hands marker frames from the io thread to the pipeline thread, oldest first. A frame gives way
// for its age, not for the number of frames behind it: one that has waited max_wait while a
// newer one waits is dropped (counted) when the pipeline comes to take, so a pipeline that falls
// behind never adds more than max_wait of latency. Frames that arrive together (the source, the
// network or the io thread held them for a while) are all processed, at the pipeline's pace, so
// the gap filler sees every frame of a burst. The newest frame is always taken. `capacity`
// preallocated slots bound the memory (plus 2: being written, being read): the writer never waits
// for the reader and nothing is allocated per frame; a burst beyond the capacity loses its oldest
// frames at once. A max_wait of 0 is "newest frame wins".

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

#include "server/ingest/marker_frame.h"
#include "server/pipeline/bounded_ring.h"

namespace skinstream::server {

class FrameMailbox {
 public:
  // 25 ms: three frame periods at 120 Hz and many times a frame's processing time, so a short
  // stall of the pipeline is caught up without a loss.
  static constexpr std::chrono::milliseconds kDefaultMaxWait{25};
  // 32 frames: a quarter of a second of 120 Hz frames arriving in one burst.
  static constexpr int kDefaultCapacity = 32;

  // Throws std::invalid_argument for a capacity below 1 or a negative max_wait.
  explicit FrameMailbox(int marker_count, std::chrono::nanoseconds max_wait = kDefaultMaxWait, int capacity = kDefaultCapacity);

  enum class DropReason {
    kWaitedTooLong,  // the pipeline was behind: waited max_wait while newer frames waited
    kMailboxFull,    // a burst longer than the capacity
  };
  // A frame that gave way, for the log.
  struct Drop {
    uint32_t frame_number = 0;
    DropReason reason = DropReason::kWaitedTooLong;
    std::chrono::nanoseconds waited{0};           // posted -> gave way
    std::chrono::nanoseconds since_last_take{0};  // the pipeline's last take (or the start) -> gave way
  };

  // Producer side (one thread): fill writable() completely, then post() it. `generation` changes
  // when the source restarts (reconnect, replay loop): the pipeline then forgets the past.
  // Returns the latest drop not reported before (at take() or at this post), if any, so the
  // producer's thread logs it and the pipeline's thread never does.
  MarkerFrame& writable() { return slots_[write_]; }
  std::optional<Drop> post(uint64_t generation);

  // Consumer side (one thread): the oldest waiting frame that has not waited too long (or the
  // newest), or nullptr after `timeout` or close(). The frame stays valid until the next take().
  const MarkerFrame* take(std::chrono::milliseconds timeout, uint64_t& out_generation);
  void close();

  uint64_t dropped() const;  // for either reason
  uint64_t dropped_waited_too_long() const;
  uint64_t dropped_mailbox_full() const;
  uint64_t posted() const;
  int waiting() const;  // posted and not yet taken
  // The counts of the mailbox this one replaces (a subject swapped), added to its own, so that
  // the subject's counters never go back.
  void add_counts_of(const FrameMailbox& replaced);

 private:
  using Clock = std::chrono::steady_clock;
  void drop_oldest(DropReason reason, Clock::time_point now);  // mutex_ held

  const std::chrono::nanoseconds max_wait_;
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::vector<MarkerFrame> slots_;
  std::vector<uint64_t> generations_;     // per slot
  std::vector<Clock::time_point> posted_at_;  // per slot
  BoundedRing<int> waiting_;              // slot indices, oldest first
  std::vector<int> free_;  // slots nobody holds; capacity reserved for all of them
  int write_ = 0, read_ = 1;
  Clock::time_point last_take_;  // the start until the first take
  bool closed_ = false;
  std::optional<Drop> unreported_drop_;
  uint64_t dropped_waited_too_long_ = 0, dropped_mailbox_full_ = 0;
  uint64_t posted_ = 0;
};

}  // namespace skinstream::server
