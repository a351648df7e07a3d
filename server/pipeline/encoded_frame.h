#pragma once
// A published frame: the Frame message in every encoding a subscriber asked for, immutable once
// published and shared by all subscribers through a reference count. The buffers come from a
// pool and go back to it when the last subscriber has written them, so steady state allocates
// nothing (the pool only grows while the number of frames held at once grows beyond what it
// was made with). Free frames are reused oldest first, so every pooled frame has its buffers
// sized for an encoding within a few frames of a subscriber asking for it, not minutes later
// when a late subscriber first holds more frames than usual.
//
// A new encoding's buffers are made off the pipeline thread: prepare() (called when a
// subscriber asks for the encoding, before the pipeline starts encoding it) allocates and
// touches one buffer per pooled frame, and the pipeline's size_message() takes one of those
// instead of allocating. Measured at start-up with 4 subscribers: the first 8 frames spent
// 3-5 ms each on fresh 640 kB buffers (page faults), which backed the mailbox up past its
// 25 ms wait limit.

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <span>
#include <vector>

#include "server/pipeline/bounded_ring.h"

namespace skinstream::server {

class FramePool;

// Which of an EncodedFrame's messages a subscriber takes, its "slot": its frame flags (the 16
// combinations of normals, quantised, markers and no positions) in version 1, and the same 16
// again in version 2 (whose Frames carry the timecode).
constexpr uint32_t encoding_slot(uint32_t frame_flags, uint16_t version) { return (frame_flags & 15u) + (version >= 2 ? 16u : 0u); }
constexpr uint32_t slot_frame_flags(uint32_t slot) { return slot & 15u; }
constexpr uint16_t slot_version(uint32_t slot) { return slot >= 16u ? 2 : 1; }

struct EncodedFrame {
  static constexpr int kEncodings = 32;  // one per slot (encoding_slot)

  uint32_t frame_number = 0;
  int64_t publish_time_ns = 0;                     // wall clock, as sent
  std::chrono::steady_clock::time_point published;  // for the subscriber queues' wait limit
  uint32_t encoded_mask = 0;  // bit s: messages[s] holds the frame for slot s
  std::array<std::vector<unsigned char>, kEncodings> messages;  // sized on first use, then reused

  std::span<const unsigned char> message(uint32_t slot) const { return messages[slot]; }
  bool has(uint32_t slot) const { return (encoded_mask >> slot) & 1u; }

 private:
  friend class FramePool;
  friend class FrameRef;
  std::atomic<int> refs_{0};
  FramePool* pool_ = nullptr;
};

// Shared ownership of a pooled frame (intrusive: copying allocates nothing).
class FrameRef {
 public:
  FrameRef() = default;
  FrameRef(const FrameRef& other);
  FrameRef(FrameRef&& other) noexcept : frame_(other.frame_) { other.frame_ = nullptr; }
  FrameRef& operator=(FrameRef other) noexcept;
  ~FrameRef();

  explicit operator bool() const { return frame_ != nullptr; }
  const EncodedFrame& operator*() const { return *frame_; }
  const EncodedFrame* operator->() const { return frame_; }
  EncodedFrame* mutable_frame() { return frame_; }  // only while the producer still fills it
  void reset();

 private:
  friend class FramePool;
  explicit FrameRef(EncodedFrame* frame);
  EncodedFrame* frame_ = nullptr;
};

class FramePool {
 public:
  explicit FramePool(int initial_frames = 0);
  FramePool(const FramePool&) = delete;
  FramePool& operator=(const FramePool&) = delete;
  ~FramePool();  // every FrameRef must be gone by then

  // A free frame (its mask cleared), or a new one when all are in use.
  FrameRef acquire();
  size_t allocated() const;

  // Any thread but the pipeline's: makes a buffer of `bytes` for slot `slot` ready for every
  // pooled frame that has none yet. Returns the number of buffers it made.
  size_t prepare(uint32_t slot, size_t bytes);
  // Pipeline thread: gives frame.messages[slot] `bytes` bytes, from a prepared buffer when one
  // is ready. Returns true when it had to allocate here instead.
  bool size_message(EncodedFrame& frame, uint32_t slot, size_t bytes);

 private:
  friend class FrameRef;
  void release(EncodedFrame* frame);

  EncodedFrame* create_locked();

  mutable std::mutex mutex_;
  std::vector<EncodedFrame*> all_;
  BoundedRing<EncodedFrame*> free_;  // room for all_: release() never allocates
  // Per encoding: buffers made by prepare() and not yet taken, and how many frames already
  // hold a buffer of that encoding (so prepare() knows how many are missing).
  std::array<std::vector<std::vector<unsigned char>>, EncodedFrame::kEncodings> ready_;
  std::array<size_t, EncodedFrame::kEncodings> sized_{};
  std::mutex prepare_mutex_;  // one prepare() at a time, so two cannot both make the missing ones
};

}  // namespace skinstream::server
