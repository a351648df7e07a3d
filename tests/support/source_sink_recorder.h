#pragma once
// For tests of the ingest sources: a SourceSink that keeps copies of everything a source hands
// on, with waits bounded in time (the sources run on support/io_thread.h's IoThread).
#include <chrono>
#include <condition_variable>
#include <functional>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/asio.h"
#include "server/ingest/source_frame.h"
#include "support/eventually.h"  // for conditions no sink call announces (a server's counter)
#include "support/io_thread.h"

namespace skinstream::test {

constexpr auto kPatience = std::chrono::seconds(20);  // bounds a failing wait; passing ones are quick

class SourceSinkRecorder : public server::SourceSink {
 public:
  void on_frame(const server::SourceFrame& frame) override {
    std::lock_guard lock(mutex);
    frames.push_back(frame);
    changed.notify_all();
  }
  void on_source_state(server::SourceState state, std::string_view detail) override {
    std::lock_guard lock(mutex);
    states.emplace_back(state, std::string(detail));
    changed.notify_all();
  }
  void on_bad_input(std::string_view what, std::string_view detail) override {
    std::lock_guard lock(mutex);
    bad_inputs.emplace_back(std::string(what) + ": " + std::string(detail));
    changed.notify_all();
  }

  bool wait(const std::function<bool()>& done) {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, kPatience, done);
  }
  bool wait_frames(size_t n) {
    return wait([&] { return frames.size() >= n; });
  }
  size_t count_state(server::SourceState s) {  // call with the mutex held (inside wait) or after the source stopped
    size_t n = 0;
    for (const auto& entry : states) n += entry.first == s ? 1 : 0;
    return n;
  }
  bool wait_state(server::SourceState s, size_t times = 1) {
    return wait([&] { return count_state(s) >= times; });
  }
  bool wait_bad_input(const std::string& what) {
    return wait([&] {
      for (const auto& b : bad_inputs)
        if (b.rfind(what + ":", 0) == 0) return true;
      return false;
    });
  }
  size_t with_frames() {
    std::lock_guard lock(mutex);
    return frames.size();
  }
  std::string last_detail(server::SourceState s) {
    std::lock_guard lock(mutex);
    for (auto it = states.rbegin(); it != states.rend(); ++it)
      if (it->first == s) return it->second;
    return {};
  }

  std::mutex mutex;
  std::condition_variable changed;
  std::vector<server::SourceFrame> frames;
  std::vector<std::pair<server::SourceState, std::string>> states;
  std::vector<std::string> bad_inputs;
};

}  // namespace skinstream::test
