#pragma once
// Hands marker frames from the io thread to the pipeline thread: newest frame wins. Three
// preallocated slots (being written, ready, being read), so the writer never waits for the
// reader and nothing is allocated per frame. A ready frame overwritten before the pipeline took
// it is counted as dropped.

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "server/ingest/marker_frame.h"

namespace skinstream::server {

class FrameMailbox {
 public:
  explicit FrameMailbox(int marker_count);

  // Producer side (one thread): fill writable() completely, then post() it. `generation` changes
  // when the source restarts (reconnect, replay loop): the pipeline then forgets the past.
  MarkerFrame& writable() { return slots_[write_]; }
  void post(uint64_t generation);

  // Consumer side (one thread): the newest frame, or nullptr after `timeout` or close(). The
  // frame stays valid until the next take().
  const MarkerFrame* take(std::chrono::milliseconds timeout, uint64_t& out_generation);
  void close();

  uint64_t dropped() const;
  uint64_t posted() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::array<MarkerFrame, 3> slots_;
  std::array<uint64_t, 3> generations_{};
  int write_ = 0, ready_ = 1, read_ = 2;
  bool has_ready_ = false;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t posted_ = 0;
};

}  // namespace skinstream::server
