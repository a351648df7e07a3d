#pragma once
// What the bench's subscribers measure: latency samples per stage, and one subscriber's tally.
#include <algorithm>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

namespace skinstream::bench {

struct Samples {
  std::vector<double> ms;
  // p50, p99, p99.9, max and count (nearest rank); sorts the samples.
  nlohmann::json summary() {
    std::sort(ms.begin(), ms.end());
    auto at = [&](double q) { return ms.empty() ? 0.0 : ms[std::min(ms.size() - 1, static_cast<size_t>(q * (ms.size() - 1) + 0.5))]; };
    return {{"p50_ms", at(0.5)}, {"p99_ms", at(0.99)}, {"p99_9_ms", at(0.999)}, {"max_ms", ms.empty() ? 0.0 : ms.back()}, {"count", ms.size()}};
  }
};

// What one subscriber thread saw: its own, so the threads share nothing while they run; merged
// after they are joined.
struct SubscriberTally {
  Samples end_to_end, processing, ingest, delivery, since_receive;  // see the report's keys
  long received = 0, unmatched = 0, out_of_order = 0;
  uint32_t dropped_first = 0, dropped_last = 0;  // the daemon's drop counter for it, first and last frame
  double longest_gap_ms = 0.0;                   // between two consecutive frames' arrivals
  uint64_t message_bytes = 0;                    // the Frame messages' bytes
  size_t model_bytes = 0;                        // the Model message (parameters)
  int64_t first_arrival_ns = 0, last_arrival_ns = 0;
  double first_frame_ms = -1.0;  // from starting to connect to the first frame (-1: none came)
  // --record-ab: the same samples split by whether a take was recording when the frame arrived
  // (index 1: recording).
  Samples end_to_end_by_recording[2], processing_by_recording[2];

  void reserve(size_t frames) {
    for (Samples* s : {&end_to_end, &processing, &ingest, &delivery, &since_receive}) s->ms.reserve(frames);
  }
  uint32_t dropped() const { return dropped_last - dropped_first; }
  // Adds another subscriber's samples and counts (not its drop counter: see dropped()).
  void add(const SubscriberTally& other) {
    auto append = [](Samples& to, const Samples& from) { to.ms.insert(to.ms.end(), from.ms.begin(), from.ms.end()); };
    append(end_to_end, other.end_to_end);
    append(processing, other.processing);
    append(ingest, other.ingest);
    append(delivery, other.delivery);
    append(since_receive, other.since_receive);
    for (int r = 0; r < 2; ++r) {
      append(end_to_end_by_recording[r], other.end_to_end_by_recording[r]);
      append(processing_by_recording[r], other.processing_by_recording[r]);
    }
    received += other.received;
    unmatched += other.unmatched;
    out_of_order += other.out_of_order;
    message_bytes += other.message_bytes;
  }
};

}  // namespace skinstream::bench
