#pragma once
// The daemon's counters and latency histograms, updated lock-free from the pipeline and io
// threads and rendered as Prometheus text for /metrics.

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace skinstream::server {

// A counter as Prometheus text: HELP, TYPE and its one sample, named skinstream_<name>.
void render_counter(std::string& out, std::string_view name, std::string_view help, uint64_t value);

// Fixed buckets (seconds) so observing never allocates. Fine between 0.1 and 10 ms, where a
// 120 Hz frame's stages and their targets (1 ms deformation, 2 ms processing, 8.3 ms between
// frames) lie: with a bucket from 1 to 2.5 ms a p99 of 1.9 ms could not be told from 2.4.
class LatencyHistogram {
 public:
  static constexpr std::array<double, 22> kBounds = {10e-6,  25e-6,  50e-6, 100e-6, 200e-6, 300e-6, 500e-6, 750e-6,
                                                     1e-3,   1.25e-3, 1.5e-3, 2e-3,  2.5e-3, 3e-3,  4e-3,  5e-3,
                                                     7.5e-3, 10e-3,  25e-3, 50e-3, 100e-3, 1.0};
  void observe_ns(int64_t ns);
  void render(std::string& out, std::string_view name, std::string_view help) const;
  // The samples alone (no HELP or TYPE), each with `labels` (e.g. subject="A") before its own.
  void render_samples(std::string& out, std::string_view name, std::string_view labels) const;
  uint64_t count() const { return count_.load(std::memory_order_relaxed); }

  // For /health and scripts: each quantile as an upper bound, the smaller of its bucket's bound
  // and the largest value observed (which also bounds a quantile beyond the last bucket).
  struct Summary {
    uint64_t count = 0;
    double p50_le_ms = 0, p99_le_ms = 0, p99_9_le_ms = 0, max_ms = 0;
  };
  Summary summary() const;
  // Each bucket's count now (not cumulative): the difference of two gives an interval's histogram.
  using Buckets = std::array<uint64_t, kBounds.size()>;
  Buckets bucket_counts() const;
  // The q-quantile (nearest rank) of `total` observations, `counts` of them in the buckets, as
  // the upper bound in ms of the bucket it falls in; `beyond_ms` when it falls beyond the last
  // bound (observations no bucket holds). /health's summary and the status line both use it.
  static double quantile_upper_bound_ms(const Buckets& counts, uint64_t total, double q, double beyond_ms);

 private:
  std::array<std::atomic<uint64_t>, kBounds.size()> buckets_{};  // non-cumulative
  std::atomic<uint64_t> count_{0};
  std::atomic<int64_t> sum_ns_{0};
  std::atomic<int64_t> max_ns_{0};
};

struct SubscriberMetrics {
  uint64_t id = 0;
  std::string transport;  // "tcp" or "websocket"
  std::string remote;
  uint64_t sent = 0;
  uint64_t dropped = 0;
};

class Metrics {
 public:
  std::atomic<uint64_t> frames_received{0};
  // The source's: numbers it skipped (frames never delivered), and new numberings (restart, loop).
  std::atomic<uint64_t> source_frames_skipped{0}, source_renumberings{0};
  std::atomic<uint64_t> frames_processed{0};
  std::atomic<uint64_t> frames_published{0};
  std::atomic<uint64_t> frames_dropped{0};  // gave way in the mailbox: waited too long, or a burst overfilled it
  std::atomic<uint64_t> frames_dropped_mailbox_full{0};  // of those, the burst's
  std::atomic<uint64_t> markers_filled{0};
  std::atomic<uint64_t> markers_relabelled{0};
  std::atomic<uint64_t> markers_held{0};
  // Times the pipeline's filler was rebuilt for a new source rate (once when the rate becomes
  // known, again only when it really changes: server/pipeline/pipeline.h).
  std::atomic<uint64_t> source_rate_changes{0};
  std::atomic<uint64_t> bad_subscriber_messages{0};
  std::atomic<uint64_t> subscribers_connected{0};  // total accepted
  std::atomic<uint64_t> subscribers_refused{0};    // Hello refused (unknown subject, ...)
  // Refused when they connected (server/publish/subscriber_admission.h), and for their token.
  std::atomic<uint64_t> subscribers_refused_not_allowed{0}, subscribers_refused_limit{0}, subscribers_refused_token{0};
  // With a token: connections refused for the places kept for those without it (all taken).
  std::atomic<uint64_t> subscribers_refused_unauthenticated{0};
  std::atomic<uint64_t> subscribers_dropped_write_stall{0};  // a write that did not progress for subscriber_write_stall_ms
  std::atomic<uint64_t> accepts_failed_no_descriptor{0};  // both ports: each pauses that port's accepts (server/listener.h)
  std::atomic<uint64_t> frame_buffers_allocated{0};              // every encoded frame buffer made
  std::atomic<uint64_t> frame_buffers_allocated_by_pipeline{0};  // of those, made on the 120 Hz thread (none prepared)
  std::atomic<uint64_t> frame_buffers_released{0};               // of an encoding nobody wanted for the hold-off

  // receive_to_take: waiting in the mailbox, the pipeline thread's wake-up included.
  LatencyHistogram receive_to_take, fill, deform, normals, encode, encode_compressed, receive_to_publish;
  // Where the capture system says how long a frame took from its cameras to leaving it (NatNet's
  // stamps): that plus receive_to_publish. The network between is not in it (no shared clock).
  LatencyHistogram source_to_publish;
  // Delivery inside the daemon, per frame and subscriber: published -> its write starts (the
  // subscriber's queue and its io thread's turn), and write started -> the socket took the last
  // byte (a subscriber that reads slowly fills its socket buffers and lengthens this one).
  LatencyHistogram subscriber_queue_wait, subscriber_write;

  void count_bad_input(std::string_view category);
  uint64_t bad_input(std::string_view category) const;
  std::map<std::string, uint64_t, std::less<>> bad_input_counts() const;

 private:
  mutable std::mutex bad_input_mutex_;
  std::map<std::string, uint64_t, std::less<>> bad_input_;
};

// One subject's metrics and its subscribers, as /metrics labels them.
struct SubjectMetricsView {
  std::string subject;
  const Metrics* metrics = nullptr;
  std::vector<SubscriberMetrics> subscribers;
};

// /metrics: the daemon's own counters (the source's frames, as skinstream_source_frames_total, its
// bad input, the failed accepts) without a subject label, then every subject's series labelled subject="NAME" (each
// metric's HELP and TYPE once, its samples for every subject after them).
std::string render_prometheus(const Metrics& source, const std::vector<SubjectMetricsView>& subjects);

}  // namespace skinstream::server
