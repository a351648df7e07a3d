#include "server/pipeline/frame_mailbox.h"

#include <stdexcept>

namespace skinstream::server {

FrameMailbox::FrameMailbox(int marker_count, int backlog)
    : backlog_(backlog >= 1 ? backlog : throw std::invalid_argument("frame mailbox: backlog below 1")),
      slots_(static_cast<size_t>(backlog) + 2, MarkerFrame(marker_count)),
      generations_(slots_.size(), 0),
      posted_at_(slots_.size()),
      last_take_(std::chrono::steady_clock::now()),
      waiting_(static_cast<size_t>(backlog)) {
  free_.reserve(slots_.size());
  for (int slot = static_cast<int>(slots_.size()) - 1; slot >= 2; --slot) free_.push_back(slot);
}

std::optional<FrameMailbox::Drop> FrameMailbox::post(uint64_t generation) {
  std::optional<Drop> drop;
  {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    generations_[write_] = generation;
    posted_at_[write_] = now;
    if (waiting_.full()) {  // the oldest waiting frame is never taken
      const int oldest = waiting_.pop();
      drop = Drop{slots_[oldest].frame_number, now - posted_at_[oldest], now - last_take_};
      free_.push_back(oldest);
      ++dropped_;
    }
    waiting_.push(write_);
    write_ = free_.back();  // one is free: backlog + 2 slots, at most backlog waiting
    free_.pop_back();
    ++posted_;
  }
  ready_cv_.notify_one();
  return drop;
}

const MarkerFrame* FrameMailbox::take(std::chrono::milliseconds timeout, uint64_t& out_generation) {
  std::unique_lock lock(mutex_);
  if (!ready_cv_.wait_for(lock, timeout, [&] { return !waiting_.empty() || closed_; }) || waiting_.empty())
    return nullptr;
  free_.push_back(read_);  // the frame taken last time is done with
  read_ = waiting_.pop();
  last_take_ = std::chrono::steady_clock::now();
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

int FrameMailbox::waiting() const {
  std::lock_guard lock(mutex_);
  return static_cast<int>(waiting_.size());
}

}  // namespace skinstream::server
