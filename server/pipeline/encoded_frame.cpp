#include "server/pipeline/encoded_frame.h"

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
  }
  frame->encoded_mask = 0;
  return FrameRef(frame);
}

size_t FramePool::allocated() const {
  std::lock_guard lock(mutex_);
  return all_.size();
}

void FramePool::release(EncodedFrame* frame) {
  std::lock_guard lock(mutex_);
  free_.push(frame);
}

}  // namespace skinstream::server
