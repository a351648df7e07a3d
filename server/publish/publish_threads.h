#pragma once
// The threads that write frames to the TCP subscribers. Each runs an io_context of its own, and
// a subscriber lives on one of them for its whole life (socket, timers, handlers), so a session
// still runs on one thread and needs no strand. New subscribers go to the thread with the fewest
// (ties: the first).
//
// Why: a 53,500-vertex frame is 640 kB per subscriber, and one io thread wrote every
// subscriber in turn, between reading the source and serving HTTP. Delivery (publish ->
// arrival) on loopback grew from 0.49 ms at the median for one subscriber to 1.05 ms for four.
// With two publish threads (skinstream-bench --publish-threads 2 against 0, alternating, 4
// subscribers): the medians are lower in every pair (delivery p50 1.11-1.21 ms against
// 1.21-1.41 over 120 s and 10 minutes), the p99s show no consistent difference on this 2-core
// machine, and in 20-30 s runs, where start-up weighs more, end-to-end p99.9 fell from 22-43 ms
// to 7-16 ms: the source's frames no longer wait while every subscriber is sent its 1.3 MB
// MeshInfo. Figures in the README.
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
