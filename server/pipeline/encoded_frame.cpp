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

FramePool::~FramePool() {
  for (EncodedFrame* f : all_) delete f;
}

FrameRef FramePool::acquire() {
  EncodedFrame* frame = nullptr;
  {
    std::lock_guard lock(mutex_);
    if (!free_.empty()) {
      frame = free_.back();
      free_.pop_back();
    } else {
      frame = new EncodedFrame();
      frame->pool_ = this;
      all_.push_back(frame);
      free_.reserve(all_.size());  // release() never allocates
    }
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
  free_.push_back(frame);
}

}  // namespace skinstream::server
