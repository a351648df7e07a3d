#include "server/pipeline/frame_mailbox.h"

#include <utility>

namespace skinstream::server {

FrameMailbox::FrameMailbox(int marker_count)
    : slots_{MarkerFrame(marker_count), MarkerFrame(marker_count), MarkerFrame(marker_count)} {}

void FrameMailbox::post(uint64_t generation) {
  {
    std::lock_guard lock(mutex_);
    generations_[write_] = generation;
    std::swap(write_, ready_);
    if (has_ready_) ++dropped_;  // the frame now in write_ was never taken
    has_ready_ = true;
    ++posted_;
  }
  ready_cv_.notify_one();
}

const MarkerFrame* FrameMailbox::take(std::chrono::milliseconds timeout, uint64_t& out_generation) {
  std::unique_lock lock(mutex_);
  if (!ready_cv_.wait_for(lock, timeout, [&] { return has_ready_ || closed_; }) || !has_ready_) return nullptr;
  std::swap(read_, ready_);
  has_ready_ = false;
  out_generation = generations_[read_];
  return &slots_[read_];
}

void FrameMailbox::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  ready_cv_.notify_all();
}

uint64_t FrameMailbox::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

uint64_t FrameMailbox::posted() const {
  std::lock_guard lock(mutex_);
  return posted_;
}

}  // namespace skinstream::server
