#pragma once
// The threads that write frames to the TCP subscribers. Each runs an io_context of its own, and
// a subscriber lives on one of them for its whole life (socket, timers, handlers), so a session
// still runs on one thread and needs no strand. New subscribers go to the thread with the fewest
// (ties: the first).
//
// Why: a 53,500-vertex frame is 640 kB per subscriber, and one io thread wrote every
// subscriber in turn, between reading the source and serving HTTP. Delivery (publish ->
// arrival) on loopback grew from 0.49 ms at the median for one subscriber to 1.05 ms for four.
// With two publish threads, in five alternating pairs of 20-30 s runs with 4 subscribers
// (skinstream-bench --publish-threads 0 | 2): delivery p50 1.30 -> 1.14 ms, end-to-end p99
// 4.66 -> 4.28 ms and p99.9 38 -> 11 ms (medians of the five runs of each); the source's frames no longer
// wait behind the writes at start-up, when every subscriber is sent a 1.3 MB MeshInfo.
//
// With count 0 there are no threads and every subscriber stays on the caller's io_context.

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "server/asio.h"

namespace skinstream::server {

class PublishThreads {
 public:
  explicit PublishThreads(int count);
  PublishThreads(const PublishThreads&) = delete;
  PublishThreads& operator=(const PublishThreads&) = delete;
  ~PublishThreads();  // stop() and join()

  int count() const { return static_cast<int>(contexts_.size()); }
  void start();
  // Where a new subscriber lives: the io_context (`fallback` when count is 0), and a token it
  // keeps for its whole life; the thread's subscriber count drops when the token goes.
  struct Placement {
    asio::io_context& io;
    std::shared_ptr<const void> token;
  };
  Placement place(asio::io_context& fallback);
  int subscribers_on(int thread) const;
  // Any thread: each context stops after the handlers already posted to it (closes first).
  void stop();
  void join();

 private:
  struct Context {
    // Shared with the tokens, which may outlive this (a session freed after the threads).
    std::shared_ptr<std::atomic<int>> subscribers = std::make_shared<std::atomic<int>>(0);
    asio::io_context io{1};
    asio::executor_work_guard<asio::io_context::executor_type> guard{io.get_executor()};
    std::thread thread;
  };
  std::vector<std::unique_ptr<Context>> contexts_;
};

}  // namespace skinstream::server
