#include "server/publish/publish_threads.h"

#include <spdlog/spdlog.h>

#include <string>

#include "server/thread_name.h"

namespace skinstream::server {

PublishThreads::PublishThreads(int count) {
  for (int i = 0; i < count; ++i) contexts_.push_back(std::make_unique<Context>());
}

PublishThreads::~PublishThreads() {
  stop();
  join();
}

void PublishThreads::start() {
  for (size_t i = 0; i < contexts_.size(); ++i)
    if (Context* c = contexts_[i].get(); !c->thread.joinable())
      c->thread = std::thread([&io = c->io, i] {
        name_this_thread("publish-" + std::to_string(i));
        try {
          io.run();
        } catch (const std::exception& e) {  // a handler that throws is a bug; say so rather than terminate
          spdlog::critical("publish thread: {}", e.what());
        }
      });
}

PublishThreads::Placement PublishThreads::place(asio::io_context& fallback) {
  if (contexts_.empty()) return {fallback, nullptr};
  int best = 0;
  for (int i = 1; i < count(); ++i)
    if (subscribers_on(i) < subscribers_on(best)) best = i;
  std::shared_ptr<std::atomic<int>> load = contexts_[best]->subscribers;
  load->fetch_add(1);
  std::shared_ptr<const void> token(load.get(), [load](const void*) { load->fetch_sub(1); });
  return {contexts_[best]->io, std::move(token)};
}

int PublishThreads::subscribers_on(int thread) const { return contexts_[thread]->subscribers->load(); }

void PublishThreads::stop() {
  for (auto& c : contexts_) asio::post(c->io, [&io = c->io] { io.stop(); });
}

void PublishThreads::join() {
  for (auto& c : contexts_)
    if (c->thread.joinable()) c->thread.join();
}

}  // namespace skinstream::server
