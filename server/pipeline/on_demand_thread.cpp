#include "server/pipeline/on_demand_thread.h"

#include "server/thread_name.h"

namespace skinstream::server {

OnDemandThread::OnDemandThread(std::string name, std::function<void()> job)
    : job_(std::move(job)), name_(std::move(name)), thread_([this] { run(); }) {}

OnDemandThread::~OnDemandThread() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  woken_.notify_one();
  thread_.join();
}

void OnDemandThread::wake() {
  {
    std::lock_guard lock(mutex_);
    asked_ = true;
  }
  woken_.notify_one();
}

void OnDemandThread::run() {
  name_this_thread(name_);
  std::unique_lock lock(mutex_);
  for (;;) {
    woken_.wait(lock, [&] { return asked_ || stopping_; });
    if (stopping_) return;
    asked_ = false;
    lock.unlock();
    job_();
    lock.lock();
  }
}

}  // namespace skinstream::server
