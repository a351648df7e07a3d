#pragma once
// An io_context running on its own thread, for tests that put a server or a source on loopback;
// call() runs a function there and waits for it.
#include <future>
#include <thread>

#include "server/asio.h"

namespace skinstream::test {

class IoThread {
 public:
  IoThread() : guard_(server::asio::make_work_guard(io)), thread_([this] { io.run(); }) {}
  ~IoThread() {
    guard_.reset();
    io.stop();
    thread_.join();
  }
  template <typename F>
  auto call(F&& f) {
    std::packaged_task<decltype(f())()> task(std::forward<F>(f));
    auto result = task.get_future();
    server::asio::post(io, [&task] { task(); });
    return result.get();
  }
  server::asio::io_context io;

 private:
  server::asio::executor_work_guard<server::asio::io_context::executor_type> guard_;
  std::thread thread_;
};

}  // namespace skinstream::test
