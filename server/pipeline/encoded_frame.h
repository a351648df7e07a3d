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
#include "server/pipeline/stream_key.h"

namespace skinstream::server {

class FramePool;

struct EncodedFrame {
  static constexpr int kEncodings = kStreamKeys;  // one per stream key (version and frame flags)

  uint32_t frame_number = 0;
  // The subject model that made it (SubscriberHub::model_epoch()): a subscriber is sent frames of
  // the model whose MeshInfo it was sent last, so none crosses a swap of the subject.
  uint32_t model_epoch = 0;
  int64_t publish_time_ns = 0;                     // wall clock, as sent
  std::chrono::steady_clock::time_point published;  // for the subscriber queues' wait limit
  StreamKeySet encoded;  // key k: messages[k] holds the frame for stream key k
  // Sized on first use, then reused. A message of the compressed encoding changes size from
  // frame to frame within its buffer's capacity (made for the largest it can be).
  std::array<std::vector<unsigned char>, kEncodings> messages;

  std::span<const unsigned char> message(StreamKey key) const { return messages[key]; }
  bool has(StreamKey key) const { return encoded.has(key); }

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

  // Any thread but the pipeline's: makes a buffer of `bytes` (the most a message of this key can
  // take) for stream key `key` ready for every pooled frame that has none yet. Returns the
  // number of buffers it made.
  size_t prepare(StreamKey key, size_t bytes);
  // Any thread: whether every pooled frame holds or has ready a buffer of `bytes` for `key`
  // (prepare() would make none).
  bool prepared(StreamKey key, size_t bytes) const;
  // Pipeline thread: gives frame.messages[key] `bytes` bytes, within its capacity, or from a
  // prepared buffer when one is ready. Returns true when it had to allocate here instead.
  bool size_message(EncodedFrame& frame, StreamKey key, size_t bytes);
  // Any thread but the pipeline's: grows the pool until at least `free_frames` frames are free.
  // New frames get a buffer of every encoding prepared so far, made here, so the pipeline does
  // not make them when subscribers hold more frames. Returns the number of buffers it made.
  size_t keep_free(size_t free_frames);
  // Any thread but the pipeline's: frees the free frames beyond the most in use at once since
  // the last trim plus `free_frames` (the oldest first; frames in use stay), so the memory that
  // stalled subscribers held comes back once they leave. Returns the number of frames freed.
  size_t trim(size_t free_frames);
  // Any thread but the pipeline's: frees the buffers of every encoding outside `wanted` that no
  // subscriber has asked for (prepare()) or held (`wanted` of an earlier call) within `hold_off`
  // before `now`: those of the free frames and the prepared ones; keep_free() no longer makes
  // them. A frame in use keeps its buffer until a later call finds it free. A subscriber that
  // asks for the encoding again gets new buffers from prepare(), off the pipeline thread, as the
  // first did. Returns the number of buffers freed.
  size_t release_unwanted(const StreamKeySet& wanted, std::chrono::steady_clock::time_point now,
                          std::chrono::steady_clock::duration hold_off);
  size_t in_use() const;
  size_t free_count() const;
  // The most frames in use at once since the last trim().
  size_t in_use_high_water() const;

 private:
  friend class FrameRef;
  void release(EncodedFrame* frame);

  EncodedFrame* create_locked();

  mutable std::mutex mutex_;
  std::vector<EncodedFrame*> all_;
  BoundedRing<EncodedFrame*> free_;  // room for all_: release() never allocates
  size_t in_use_high_water_ = 0;
  // Per encoding: buffers made by prepare() and not yet taken, and how many frames already
  // hold a buffer of that encoding (so prepare() knows how many are missing).
  std::array<std::vector<std::vector<unsigned char>>, EncodedFrame::kEncodings> ready_;
  std::array<size_t, EncodedFrame::kEncodings> sized_{};
  std::array<size_t, EncodedFrame::kEncodings> prepared_bytes_{};  // per encoding, from prepare()
  // Per encoding: when a subscriber last asked for it or was seen holding it.
  std::array<std::chrono::steady_clock::time_point, EncodedFrame::kEncodings> last_wanted_{};
  std::mutex prepare_mutex_;  // one prepare() at a time, so two cannot both make the missing ones
};

}  // namespace skinstream::server
