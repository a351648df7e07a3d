#pragma once
// A thread that runs one job each time it is asked, off the thread that asks: wake() only sets
// a flag and signals (it never allocates and never waits for the job), and asks that come while
// the job runs make it run once more after. The pipeline thread uses it to have its frame pool
// grown without allocating there.

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace skinstream::server {

class OnDemandThread {
 public:
  // `name` names the thread (server/thread_name.h).
  OnDemandThread(std::string name, std::function<void()> job);
  OnDemandThread(const OnDemandThread&) = delete;
  OnDemandThread& operator=(const OnDemandThread&) = delete;
  ~OnDemandThread();  // lets a job under way finish, then joins

  void wake();

 private:
  void run();

  std::function<void()> job_;
  std::mutex mutex_;
  std::condition_variable woken_;
  bool asked_ = false, stopping_ = false;
  std::string name_;
  std::thread thread_;  // last: started once the rest is made
};

}  // namespace skinstream::server
