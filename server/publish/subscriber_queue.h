#pragma once
// One subscriber's outgoing queue. Frames: a bounded ring where the newest frame wins (pushing
// into a full ring drops the oldest, counted). Control messages (MeshInfo, Status) go ahead of
// frames and are bounded too: when too many wait, the oldest Status is dropped (a newer one
// says more). Filled by the pipeline thread, emptied by the io thread.

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

  explicit SubscriberQueue(int frame_capacity);

  void push_frame(const FrameRef& frame);  // never blocks for long, never allocates
  void push_control(ControlMessage message);

  struct Item {
    ControlMessage control;  // either this
    FrameRef frame;          // or this
  };
  // What pop() may take after the control messages, which always go first.
  enum class Take {
    OldestFrame,  // frames in order
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
  mutable std::mutex mutex_;
  std::vector<FrameRef> ring_;
  size_t head_ = 0, count_ = 0;
  std::deque<ControlMessage> control_;
  uint64_t dropped_ = 0;
};

}  // namespace skinstream::server
