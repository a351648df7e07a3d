#include "server/pipeline/frame_mailbox.h"

#include <stdexcept>

namespace skinstream::server {

FrameMailbox::FrameMailbox(int marker_count, std::chrono::nanoseconds max_wait, int capacity)
    : max_wait_(max_wait >= std::chrono::nanoseconds{0} ? max_wait : throw std::invalid_argument("frame mailbox: negative max_wait")),
      slots_(static_cast<size_t>(capacity >= 1 ? capacity : throw std::invalid_argument("frame mailbox: capacity below 1")) + 2,
             MarkerFrame(marker_count)),
      generations_(slots_.size(), 0),
      posted_at_(slots_.size()),
      waiting_(static_cast<size_t>(capacity)),
      last_take_(Clock::now()) {
  free_.reserve(slots_.size());
  for (int slot = static_cast<int>(slots_.size()) - 1; slot >= 2; --slot) free_.push_back(slot);
}

void FrameMailbox::drop_oldest(DropReason reason, Clock::time_point now) {
  const int oldest = waiting_.pop();
  unreported_drop_ = Drop{slots_[oldest].frame_number, reason, now - posted_at_[oldest], now - last_take_};
  free_.push_back(oldest);
  ++(reason == DropReason::kMailboxFull ? dropped_mailbox_full_ : dropped_waited_too_long_);
}

std::optional<FrameMailbox::Drop> FrameMailbox::post(uint64_t generation) {
  std::optional<Drop> drop;
  {
    const auto now = Clock::now();
    std::lock_guard lock(mutex_);
    generations_[write_] = generation;
    posted_at_[write_] = now;
    if (waiting_.full()) drop_oldest(DropReason::kMailboxFull, now);  // the oldest waiting frame is never taken
    waiting_.push(write_);
    write_ = free_.back();  // one is free: capacity + 2 slots, at most capacity waiting
    free_.pop_back();
    ++posted_;
    drop.swap(unreported_drop_);
  }
  ready_cv_.notify_one();
  return drop;
}

const MarkerFrame* FrameMailbox::take(std::chrono::milliseconds timeout, uint64_t& out_generation) {
  std::unique_lock lock(mutex_);
  if (!ready_cv_.wait_for(lock, timeout, [&] { return !waiting_.empty() || closed_; }) || waiting_.empty())
    return nullptr;
  const auto now = Clock::now();
  while (waiting_.size() > 1 && now - posted_at_[waiting_.front()] >= max_wait_) drop_oldest(DropReason::kWaitedTooLong, now);
  free_.push_back(read_);  // the frame taken last time is done with
  read_ = waiting_.pop();
  last_take_ = now;
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
  return dropped_waited_too_long_ + dropped_mailbox_full_;
}

void FrameMailbox::add_counts_of(const FrameMailbox& replaced) {
  const uint64_t waited = replaced.dropped_waited_too_long(), full = replaced.dropped_mailbox_full(),
                 posted = replaced.posted();
  std::lock_guard lock(mutex_);
  dropped_waited_too_long_ += waited;
  dropped_mailbox_full_ += full;
  posted_ += posted;
}

uint64_t FrameMailbox::dropped_waited_too_long() const {
  std::lock_guard lock(mutex_);
  return dropped_waited_too_long_;
}

uint64_t FrameMailbox::dropped_mailbox_full() const {
  std::lock_guard lock(mutex_);
  return dropped_mailbox_full_;
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
