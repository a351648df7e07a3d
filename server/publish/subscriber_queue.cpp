#include "server/publish/subscriber_queue.h"

#include <algorithm>

namespace skinstream::server {

SubscriberQueue::SubscriberQueue(int frame_capacity, std::chrono::nanoseconds max_wait)
    : max_wait_(max_wait), ring_(static_cast<size_t>(std::max(1, frame_capacity))) {}

template <typename Predicate>
void SubscriberQueue::drop_oldest_while(Predicate should) {
  for (;;) {  // one at a time, each released outside the lock
    FrameRef older;
    std::lock_guard lock(mutex_);
    if (count_ == 0 || !should(*ring_[head_])) return;
    older = std::move(ring_[head_]);
    head_ = (head_ + 1) % ring_.size();
    --count_;
    ++dropped_;
  }
}

void SubscriberQueue::push_frame(const FrameRef& frame) {
  // The new frame is newer than every queued one: those that waited too long give way to it, and
  // the oldest when the ring is full (only this thread pushes, so the ring stays below full).
  const auto now = std::chrono::steady_clock::now();
  drop_oldest_while([&](const EncodedFrame& oldest) { return count_ == ring_.size() || now - oldest.published >= max_wait_; });
  std::lock_guard lock(mutex_);
  ring_[(head_ + count_) % ring_.size()] = frame;
  ++count_;
}

void SubscriberQueue::push_control(ControlMessage message) {
  std::lock_guard lock(mutex_);
  if (control_.size() >= kMaxControl) {
    // Drop the oldest Status (byte 6 of a message is its type); a MeshInfo must get through.
    auto status = std::find_if(control_.begin(), control_.end(), [](const ControlMessage& m) { return m->size() > 6 && (*m)[6] == 4; });
    control_.erase(status != control_.end() ? status : control_.begin());
  }
  control_.push_back(std::move(message));
}

bool SubscriberQueue::pop(Item& out, Take take) {
  // The predicates run with mutex_ held (by drop_oldest_while).
  if (take == Take::NewestFrame) drop_oldest_while([&](const EncodedFrame&) { return count_ > 1 && control_.empty(); });
  if (take == Take::OldestFrame) {
    const auto now = std::chrono::steady_clock::now();
    drop_oldest_while([&](const EncodedFrame& oldest) { return count_ > 1 && now - oldest.published >= max_wait_; });
  }
  std::lock_guard lock(mutex_);
  if (!control_.empty()) {
    out.control = std::move(control_.front());
    control_.pop_front();
    out.frame.reset();
    return true;
  }
  if (count_ == 0 || take == Take::ControlOnly) return false;
  out.control.reset();
  out.frame = std::move(ring_[head_]);
  head_ = (head_ + 1) % ring_.size();
  --count_;
  return true;
}

bool SubscriberQueue::has_control() const {
  std::lock_guard lock(mutex_);
  return !control_.empty();
}

bool SubscriberQueue::empty() const {
  std::lock_guard lock(mutex_);
  return control_.empty() && count_ == 0;
}

uint64_t SubscriberQueue::frames_dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

size_t SubscriberQueue::frames_queued() const {
  std::lock_guard lock(mutex_);
  return count_;
}

}  // namespace skinstream::server
