#include "server/record/take_tap.h"

#include <algorithm>

namespace skinstream::server {

TakeTap::TakeTap(std::string subject, std::vector<std::string> marker_names, int unlabelled_slots,
                 size_t ring_frames)
    : subject_(std::move(subject)),
      marker_names_(std::move(marker_names)),
      unlabelled_slots_(std::max(unlabelled_slots, 0)),
      received_(ring_frames, marker_names_.size() + static_cast<size_t>(unlabelled_slots_),
                static_cast<size_t>(unlabelled_slots_)),
      published_(ring_frames, marker_names_.size()) {}

std::vector<std::string> TakeTap::received_labels() const {
  std::vector<std::string> labels = marker_names_;
  for (int i = 1; i <= unlabelled_slots_; ++i) labels.push_back("*" + std::to_string(i));
  return labels;
}

RecordedFrame* TakeTap::claim(RecordedFrameRing& ring, std::atomic<uint64_t>& dropped, uint32_t frame_number,
                              int64_t source_time_ns, int64_t receive_time_ns) {
  const uint64_t take = take_.load(std::memory_order_acquire);
  if (take == 0) return nullptr;
  RecordedFrame* slot = ring.claim();
  if (!slot) {
    dropped.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  slot->take = take;
  slot->frame_number = frame_number;
  slot->source_time_ns = source_time_ns;
  slot->receive_time_ns = receive_time_ns;
  return slot;
}

void TakeTap::record_received(const MarkerFrame& frame) {
  if (frame.source_rate_hz > 0) source_rate_hz_.store(frame.source_rate_hz, std::memory_order_relaxed);
  RecordedFrame* slot =
      claim(received_, received_dropped_, frame.frame_number, frame.source_time_ns, frame.receive_time_ns);
  if (!slot) return;
  slot->timecode = frame.timecode;
  const size_t markers = std::min(marker_names_.size(), frame.labelled.size());
  std::copy_n(frame.labelled.begin(), markers, slot->points.begin());
  std::fill(slot->points.begin() + static_cast<long>(markers),
            slot->points.begin() + static_cast<long>(marker_names_.size()), missing_point());
  const int kept = std::min(frame.unlabelled_count, unlabelled_slots_);
  const auto unlabelled = slot->points.begin() + static_cast<long>(marker_names_.size());
  std::copy_n(frame.unlabelled.begin(), kept, unlabelled);
  std::fill(unlabelled + kept, slot->points.end(), missing_point());
  std::copy_n(frame.unlabelled_ids.begin(), kept, slot->unlabelled_ids.begin());
  slot->unlabelled_copied = kept;
  slot->unlabelled = frame.unlabelled_count;
  slot->unknown_labels = frame.unknown_labels;
  received_.publish();
}

void TakeTap::on_filled(const FilledFrameView& frame) {
  RecordedFrame* slot =
      claim(published_, published_dropped_, frame.frame_number, frame.source_time_ns, frame.receive_time_ns);
  if (!slot) return;
  slot->timecode = SourceTimecode{};
  const size_t markers = std::min(marker_names_.size(), frame.positions.size());
  std::copy_n(frame.positions.begin(), markers, slot->points.begin());
  std::fill(slot->points.begin() + static_cast<long>(markers), slot->points.end(), missing_point());
  for (size_t m = 0; m < slot->status.size(); ++m)
    slot->status[m] = m < frame.status.size() ? static_cast<uint8_t>(frame.status[m])
                                              : static_cast<uint8_t>(MarkerStatus::Held);
  published_.publish();
}

}  // namespace skinstream::server
