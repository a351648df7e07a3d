#include "server/pipeline/encoded_frame.h"

#include <malloc.h>

#include <algorithm>
#include <utility>

namespace skinstream::server {

FrameRef::FrameRef(EncodedFrame* frame) : frame_(frame) {
  if (frame_) frame_->refs_.fetch_add(1, std::memory_order_relaxed);
}

FrameRef::FrameRef(const FrameRef& other) : frame_(other.frame_) {
  if (frame_) frame_->refs_.fetch_add(1, std::memory_order_relaxed);
}

FrameRef& FrameRef::operator=(FrameRef other) noexcept {
  std::swap(frame_, other.frame_);
  return *this;
}

FrameRef::~FrameRef() { reset(); }

void FrameRef::reset() {
  if (frame_ && frame_->refs_.fetch_sub(1, std::memory_order_acq_rel) == 1) frame_->pool_->release(frame_);
  frame_ = nullptr;
}

FramePool::FramePool(int initial_frames) {
  std::lock_guard lock(mutex_);
  for (int i = 0; i < initial_frames; ++i) create_locked();
  for (EncodedFrame* frame : all_) free_.push(frame);
}

FramePool::~FramePool() {
  for (EncodedFrame* f : all_) delete f;
}

// With no frame free: a new one, and the ring grown to hold every frame, so release() never
// allocates.
EncodedFrame* FramePool::create_locked() {
  EncodedFrame* frame = new EncodedFrame();
  frame->pool_ = this;
  all_.push_back(frame);
  free_.reset(all_.size());
  return frame;
}

FrameRef FramePool::acquire() {
  EncodedFrame* frame = nullptr;
  {
    std::lock_guard lock(mutex_);
    frame = free_.empty() ? create_locked() : free_.pop();
    in_use_high_water_ = std::max(in_use_high_water_, all_.size() - free_.size());
  }
  frame->encoded = {};
  return FrameRef(frame);
}

size_t FramePool::allocated() const {
  std::lock_guard lock(mutex_);
  return all_.size();
}

size_t FramePool::prepare(StreamKey key, size_t bytes) {
  if (key >= EncodedFrame::kEncodings || bytes == 0) return 0;
  std::lock_guard serial(prepare_mutex_);
  size_t missing = 0;
  {
    std::lock_guard lock(mutex_);
    prepared_bytes_[key] = bytes;
    last_wanted_[key] = std::chrono::steady_clock::now();
    const size_t covered = sized_[key] + ready_[key].size();
    missing = all_.size() > covered ? all_.size() - covered : 0;
  }
  // Made outside the lock: value-initialised, so every page is touched here and not on the
  // pipeline thread.
  std::vector<std::vector<unsigned char>> made;
  made.reserve(missing);
  for (size_t i = 0; i < missing; ++i) made.emplace_back(bytes);
  std::lock_guard lock(mutex_);
  for (auto& buffer : made) ready_[key].push_back(std::move(buffer));
  return missing;
}

bool FramePool::prepared(StreamKey key, size_t bytes) const {
  if (key >= EncodedFrame::kEncodings || bytes == 0) return false;
  std::lock_guard lock(mutex_);
  return prepared_bytes_[key] == bytes && sized_[key] + ready_[key].size() >= all_.size();
}

bool FramePool::size_message(EncodedFrame& frame, StreamKey key, size_t bytes) {
  std::vector<unsigned char>& message = frame.messages[key];
  if (message.size() == bytes) return false;
  if (message.capacity() >= bytes) {  // a compressed message, smaller or larger than the last
    message.resize(bytes);
    return false;
  }
  std::lock_guard lock(mutex_);
  if (message.capacity() == 0) ++sized_[key];  // this frame now holds the encoding, either way
  std::vector<std::vector<unsigned char>>& ready = ready_[key];
  if (!ready.empty() && ready.back().capacity() >= bytes) {
    message.swap(ready.back());
    message.resize(bytes);
    ready.pop_back();  // the frame's old buffer, empty unless the size changed (never, for one mesh)
    return false;
  }
  message.resize(bytes);
  return true;
}

size_t FramePool::in_use() const {
  std::lock_guard lock(mutex_);
  return all_.size() - free_.size();
}

size_t FramePool::free_count() const {
  std::lock_guard lock(mutex_);
  return free_.size();
}

size_t FramePool::in_use_high_water() const {
  std::lock_guard lock(mutex_);
  return in_use_high_water_;
}

size_t FramePool::keep_free(size_t free_frames) {
  std::lock_guard serial(prepare_mutex_);
  std::array<size_t, EncodedFrame::kEncodings> bytes{};
  size_t missing = 0;
  {
    std::lock_guard lock(mutex_);
    bytes = prepared_bytes_;
    missing = free_frames > free_.size() ? free_frames - free_.size() : 0;
  }
  if (missing == 0) return 0;
  // Made outside the lock, every page touched here (value-initialised), as prepare() does.
  std::vector<EncodedFrame*> made(missing);
  size_t buffers = 0;
  for (EncodedFrame*& frame : made) {
    frame = new EncodedFrame();
    frame->pool_ = this;
    for (size_t key = 0; key < bytes.size(); ++key)
      if (bytes[key] > 0) {
        frame->messages[key].resize(bytes[key]);
        ++buffers;
      }
  }
  std::lock_guard lock(mutex_);
  // The ring grows to hold every frame, its free frames kept in order.
  std::vector<EncodedFrame*> free_frames_now;
  while (!free_.empty()) free_frames_now.push_back(free_.pop());
  free_.reset(all_.size() + made.size());
  for (EncodedFrame* frame : free_frames_now) free_.push(frame);
  for (EncodedFrame* frame : made) {
    all_.push_back(frame);
    free_.push(frame);
    for (size_t key = 0; key < bytes.size(); ++key) sized_[key] += bytes[key] > 0;
  }
  return buffers;
}

size_t FramePool::trim(size_t free_frames) {
  std::lock_guard serial(prepare_mutex_);
  std::vector<EncodedFrame*> doomed;
  {
    std::lock_guard lock(mutex_);
    const size_t keep = in_use_high_water_ + free_frames;
    in_use_high_water_ = all_.size() - free_.size();  // the next trim looks at what comes after this one
    // The oldest free frames go first; their prepared buffers beyond the frames left go too.
    while (all_.size() > keep && !free_.empty()) {
      EncodedFrame* frame = free_.pop();
      all_.erase(std::find(all_.begin(), all_.end(), frame));
      for (size_t key = 0; key < frame->messages.size(); ++key) sized_[key] -= frame->messages[key].capacity() > 0;
      doomed.push_back(frame);
    }
    for (size_t key = 0; key < ready_.size(); ++key)
      while (!ready_[key].empty() && sized_[key] + ready_[key].size() > all_.size()) ready_[key].pop_back();
  }
  for (EncodedFrame* frame : doomed) delete frame;
  // Buffers of 640 kB may sit in malloc's heap rather than in mappings of their own (its
  // threshold rises as it frees them): hand the freed pages back to the system too.
  if (!doomed.empty()) malloc_trim(0);
  return doomed.size();
}

size_t FramePool::release_unwanted(const StreamKeySet& wanted, std::chrono::steady_clock::time_point now,
                                   std::chrono::steady_clock::duration hold_off) {
  // Serial with prepare(): a subscriber asking for an encoding while this runs either comes
  // first (and its fresh last_wanted_ keeps the buffers) or after (and makes them again).
  std::lock_guard serial(prepare_mutex_);
  // Freed outside the lock, and sized before it: the pipeline takes mutex_ for every frame, so
  // nothing here may allocate while holding it. Under prepare_mutex_ the buffers of an encoding,
  // held by frames or ready, can only move between the two (size_message), never grow.
  std::vector<std::vector<unsigned char>> doomed;
  {
    size_t most = 0;
    {
      std::lock_guard lock(mutex_);
      for (size_t key = 0; key < ready_.size(); ++key) most += sized_[key] + ready_[key].size();
    }
    doomed.reserve(most);
  }
  {
    std::lock_guard lock(mutex_);
    for (StreamKey key = 0; key < EncodedFrame::kEncodings; ++key) {
      if (wanted.has(key)) {
        last_wanted_[key] = now;
        continue;
      }
      if (now - last_wanted_[key] < hold_off || (sized_[key] == 0 && ready_[key].empty())) continue;
      prepared_bytes_[key] = 0;
      for (auto& buffer : ready_[key]) doomed.push_back(std::move(buffer));
      ready_[key].clear();
      for (size_t i = 0; i < free_.size(); ++i) {
        std::vector<unsigned char>& message = free_.at(i)->messages[key];
        if (message.capacity() == 0) continue;
        doomed.emplace_back().swap(message);
        --sized_[key];
      }
    }
  }
  const size_t freed = doomed.size();
  doomed.clear();
  if (freed > 0) malloc_trim(0);  // the pages back to the system too, as trim() does
  return freed;
}

void FramePool::release(EncodedFrame* frame) {
  std::lock_guard lock(mutex_);
  free_.push(frame);
}

}  // namespace skinstream::server
