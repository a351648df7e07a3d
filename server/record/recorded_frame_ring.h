#pragma once
// The hand-off of recorded frames from one producing thread (the io thread for what was
// received, the pipeline thread for what was published) to the take writer's thread, without a
// lock and without allocating: slots are made once, the producer fills the next free one in
// place or, when the writer is behind by the whole ring, counts the frame as dropped and goes
// on. The producer never waits for the disk.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/capture.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

struct RecordedFrame {
  uint64_t take = 0;  // the take it was recorded for: a frame of a stopped take is not written
  uint32_t frame_number = 0;
  int64_t source_time_ns = 0;
  int64_t receive_time_ns = 0;
  SourceTimecode timecode;
  // Received: the labelled markers, then the frame's first unlabelled points; published: the markers.
  std::vector<Vec3> points;
  std::vector<uint8_t> status;      // published: MarkerStatus per marker
  std::vector<int> unlabelled_ids;  // received: the source's trajectory id of each unlabelled point copied
  int unlabelled_copied = 0;        // received: unlabelled points copied
  int unlabelled = 0;      // received: unlabelled points of the frame (those not copied are not kept)
  int unknown_labels = 0;  // received: labels the subject does not have
};

class RecordedFrameRing {
 public:
  // `slots` frames of `points` points (and as many status bytes), `unlabelled` of them
  // unlabelled points with their ids. Allocates.
  RecordedFrameRing(size_t slots, size_t points, size_t unlabelled = 0) : slots_(slots) {
    for (RecordedFrame& slot : slots_) {
      slot.points.assign(points, missing_point());
      slot.status.assign(points, 0);
      slot.unlabelled_ids.assign(unlabelled, -1);
    }
  }
  RecordedFrameRing(const RecordedFrameRing&) = delete;
  RecordedFrameRing& operator=(const RecordedFrameRing&) = delete;

  // Producer: the slot to fill, or null when the ring is full. Then publish() it.
  RecordedFrame* claim() {
    const uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == slots_.size()) return nullptr;
    return &slots_[tail % slots_.size()];
  }
  void publish() { tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

  // Consumer: the oldest published slot, or null. Then pop() it when done with it.
  const RecordedFrame* front() const {
    const uint64_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[head % slots_.size()];
  }
  void pop() { head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

  size_t capacity() const { return slots_.size(); }

 private:
  std::vector<RecordedFrame> slots_;
  alignas(64) std::atomic<uint64_t> head_{0};  // consumer's
  alignas(64) std::atomic<uint64_t> tail_{0};  // producer's
};

}  // namespace skinstream::server
