#pragma once
// One subscriber's outgoing queue. Frames: a bounded ring, oldest first, where a frame gives way
// (counted) when it has waited `max_wait` since it was published while a newer one waits, or
// when the ring is full. So a burst of frames reaches a subscriber whole when it reads them
// within max_wait, a slow one gets the newest frames no older than that, and a stalled one holds
// only the frames of the last max_wait (the pool's buffers stay few). Control messages
// (MeshInfo, Status) go ahead of frames and are bounded too: when too many wait, the oldest
// Status is dropped (a newer one says more). Filled by the pipeline thread, emptied by the io
// thread.

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

#include "server/pipeline/encoded_frame.h"

namespace skinstream::server {

using ControlMessage = std::shared_ptr<const std::vector<unsigned char>>;

class SubscriberQueue {
 public:
  static constexpr size_t kMaxControl = 8;

  // No wait limit by default: only the capacity bounds the ring (newest wins when full).
  explicit SubscriberQueue(int frame_capacity, std::chrono::nanoseconds max_wait = std::chrono::nanoseconds::max());

  void push_frame(const FrameRef& frame);  // never blocks for long, never allocates
  void push_control(ControlMessage message);

  struct Item {
    ControlMessage control;  // either this
    FrameRef frame;          // or this
  };
  // What pop() may take after the control messages, which always go first.
  enum class Take {
    OldestFrame,  // frames in order (those that waited too long while a newer one waits are dropped)
    NewestFrame,  // the newest frame; the older ones are dropped (counted)
    ControlOnly,  // no frame
  };
  // False when there is nothing to take.
  bool pop(Item& out, Take take = Take::OldestFrame);
  bool empty() const;
  bool has_control() const;

  uint64_t frames_dropped() const;
  size_t frames_queued() const;

 private:
  // Drops the oldest frame, released outside the lock, while `should` says so of it (with
  // mutex_ not held by the caller).
  template <typename Predicate>
  void drop_oldest_while(Predicate should);

  const std::chrono::nanoseconds max_wait_;
  mutable std::mutex mutex_;
  std::vector<FrameRef> ring_;
  size_t head_ = 0, count_ = 0;
  std::deque<ControlMessage> control_;
  uint64_t dropped_ = 0;
};

}  // namespace skinstream::server
