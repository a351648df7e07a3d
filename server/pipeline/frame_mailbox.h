#pragma once
// Hands marker frames from the io thread to the pipeline thread, oldest first, with a short
// bounded backlog. Frames that arrive together (the io thread was descheduled, the network
// held them) are all processed, so the gap filler sees every frame; when the pipeline falls
// behind by more than the backlog, the oldest waiting frame gives way (counted as dropped),
// so the newest frame always gets in and the added latency stays bounded. backlog + 2
// preallocated slots (being written, being read, the waiting ones): the writer never waits for
// the reader and nothing is allocated per frame. A backlog of 1 is "newest frame wins".

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
  // 3 frames: 25 ms at 120 Hz, several times a frame's processing time, so a stall of the
  // pipeline or a burst from the io thread of that length is caught up without a loss.
  static constexpr int kDefaultBacklog = 3;

  // Throws std::invalid_argument for a backlog below 1.
  explicit FrameMailbox(int marker_count, int backlog = kDefaultBacklog);

  // What a frame that gave way tells about why: one that waited long while the pipeline took
  // nothing says the pipeline stalled; one that waited a fraction of a frame period says frames
  // arrived in a burst (the io thread or the network held them).
  struct Drop {
    uint32_t frame_number = 0;
    std::chrono::nanoseconds waited{0};           // posted -> gave way
    std::chrono::nanoseconds since_last_take{0};  // the pipeline's last take (or the start) -> now
  };

  // Producer side (one thread): fill writable() completely, then post() it. `generation` changes
  // when the source restarts (reconnect, replay loop): the pipeline then forgets the past.
  // Returns the frame that gave way to this one, if any.
  MarkerFrame& writable() { return slots_[write_]; }
  std::optional<Drop> post(uint64_t generation);

  // Consumer side (one thread): the oldest waiting frame, or nullptr after `timeout` or close().
  // The frame stays valid until the next take().
  const MarkerFrame* take(std::chrono::milliseconds timeout, uint64_t& out_generation);
  void close();

  uint64_t dropped() const;
  uint64_t posted() const;
  int waiting() const;  // posted and not yet taken

 private:
  const int backlog_;
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::vector<MarkerFrame> slots_;
  std::vector<uint64_t> generations_;  // per slot
  std::vector<std::chrono::steady_clock::time_point> posted_at_;  // per slot
  std::chrono::steady_clock::time_point last_take_;  // the start until the first take
  BoundedRing<int> waiting_;           // slot indices, oldest first
  std::vector<int> free_;  // slots nobody holds; capacity reserved for all of them
  int write_ = 0, read_ = 1;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t posted_ = 0;
};

}  // namespace skinstream::server
