#pragma once
// One subject's side of the take recorder: what the daemon received for it (on the io thread)
// and what it published (on the pipeline thread) copied, while a take is recording, into
// preallocated rings the take writer's thread empties. The copy is all the threads of the
// stream ever do for a recording: no file, no lock, no allocation; a ring the writer has not
// emptied in time drops the frame for the take (counted), never for the subscribers.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "server/ingest/marker_frame.h"
#include "server/pipeline/filled_frame_observer.h"
#include "server/record/recorded_frame_ring.h"

namespace skinstream::server {

class TakeTap : public FilledFrameObserver {
 public:
  // `unlabelled_slots`: unlabelled points kept per received frame (after the labelled markers;
  // the take writer puts each in a channel by its trajectory: server/record/unlabelled_slots.h).
  TakeTap(std::string subject, std::vector<std::string> marker_names, int unlabelled_slots,
          size_t ring_frames);

  const std::string& subject() const { return subject_; }
  const std::vector<std::string>& marker_names() const { return marker_names_; }
  int unlabelled_slots() const { return unlabelled_slots_; }
  // The received take's channels: the markers, then "*1".."*N" for the unlabelled slots.
  std::vector<std::string> received_labels() const;

  // The io thread, for each frame routed to this subject.
  void record_received(const MarkerFrame& frame);
  // The pipeline thread, for each frame published.
  void on_filled(const FilledFrameView& frame) override;

  // The recorder: record for take `take` from now on; 0 stops.
  void set_take(uint64_t take) { take_.store(take, std::memory_order_release); }
  RecordedFrameRing& received() { return received_; }
  RecordedFrameRing& published() { return published_; }
  uint64_t received_dropped() const { return received_dropped_.load(std::memory_order_relaxed); }
  uint64_t published_dropped() const { return published_dropped_.load(std::memory_order_relaxed); }
  // The source's frame rate as last received (0: not known yet).
  double source_rate_hz() const { return source_rate_hz_.load(std::memory_order_relaxed); }

 private:
  // The ring's next slot stamped with the take and the frame's numbers, or null: no take records,
  // or the ring is full (counted in `dropped`).
  RecordedFrame* claim(RecordedFrameRing& ring, std::atomic<uint64_t>& dropped, uint32_t frame_number,
                       int64_t source_time_ns, int64_t receive_time_ns);

  std::string subject_;
  std::vector<std::string> marker_names_;
  int unlabelled_slots_ = 0;
  std::atomic<uint64_t> take_{0};
  std::atomic<double> source_rate_hz_{0.0};
  RecordedFrameRing received_, published_;
  std::atomic<uint64_t> received_dropped_{0}, published_dropped_{0};
};

}  // namespace skinstream::server
