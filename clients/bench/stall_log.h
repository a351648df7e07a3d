#pragma once
// When a benchmark run hitched, and who saw it, on one time line: the replay server's late sends,
// each subscriber's long waits between frames, the frames the daemon dropped for a subscriber
// and those its pipeline dropped. So a run with drops says whether the whole machine paused (the replay and every
// subscriber at the same moment) or one subscriber fell behind on its own (its own gap, its own
// drops). Written from the replay's io thread and the subscriber threads, only when something
// happens, so a mutex costs nothing on the frames in between.
#include <algorithm>
#include <cstdint>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace skinstream::bench {

class StallLog {
 public:
  explicit StallLog(size_t capacity = 200) : capacity_(capacity) {}

  // Events before this (the warm-up) are not kept; times are reported from here.
  void start(int64_t start_ns) {
    std::lock_guard lock(mutex_);
    start_ns_ = start_ns;
    started_ = true;
  }

  // at_ns: when the silence began (a gap) or when the drop was seen (a drop).
  void add_gap(int64_t at_ns, const std::string& who, double gap_ms) { add({at_ns, who, gap_ms, 0}); }
  void add_drop(int64_t at_ns, const std::string& who, uint32_t frames) { add({at_ns, who, 0.0, frames}); }

  // Sorted by time: {"at_s", "who", "gap_ms"} or {"at_s", "who", "dropped"}; and how many events
  // did not fit.
  nlohmann::json to_json() const {
    std::lock_guard lock(mutex_);
    std::vector<Event> sorted = events_;
    std::stable_sort(sorted.begin(), sorted.end(), [](const Event& a, const Event& b) { return a.at_ns < b.at_ns; });
    nlohmann::json list = nlohmann::json::array();
    for (const Event& e : sorted) {
      nlohmann::json row = {{"at_s", static_cast<double>(e.at_ns - start_ns_) / 1e9}, {"who", e.who}};
      if (e.dropped > 0) row["dropped"] = e.dropped;
      else row["gap_ms"] = e.gap_ms;
      list.push_back(row);
    }
    return {{"events", list}, {"events_not_kept", not_kept_}};
  }

 private:
  struct Event {
    int64_t at_ns;
    std::string who;
    double gap_ms;
    uint32_t dropped;
  };
  void add(Event event) {
    std::lock_guard lock(mutex_);
    if (!started_ || event.at_ns < start_ns_) return;
    if (events_.size() >= capacity_) {
      ++not_kept_;
      return;
    }
    events_.push_back(std::move(event));
  }

  const size_t capacity_;
  mutable std::mutex mutex_;
  bool started_ = false;
  int64_t start_ns_ = 0;
  std::vector<Event> events_;
  uint64_t not_kept_ = 0;
};

}  // namespace skinstream::bench
