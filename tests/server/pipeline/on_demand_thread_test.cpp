// The thread that runs a job when asked: the asker never waits for it, asks while it runs make
// it run once more, and it runs on a thread of its own, named.
#include "server/pipeline/on_demand_thread.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>

#include "server/thread_name.h"
#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

TEST(OnDemandThread, RunsTheJobOnItsOwnNamedThreadWhenWoken) {
  std::promise<std::pair<std::thread::id, std::string>> where;
  std::atomic<int> runs{0};
  OnDemandThread thread("pool-test", [&] {
    if (runs.fetch_add(1) == 0) where.set_value({std::this_thread::get_id(), this_thread_name()});
  });
  EXPECT_EQ(runs.load(), 0) << "ran before it was asked";
  thread.wake();
  const auto [id, name] = where.get_future().get();
  EXPECT_NE(id, std::this_thread::get_id());
  EXPECT_EQ(name, "pool-test");
}

// While the job runs, any number of asks make it run once more, not once each, and the asker
// neither waits for the job nor allocates.
TEST(OnDemandThread, AsksWhileTheJobRunsCoalesceAndNeverWait) {
  std::atomic<int> runs{0};
  std::promise<void> first_started, second_started;
  std::promise<void> release_promise;
  const std::shared_future<void> release = release_promise.get_future().share();
  OnDemandThread thread("coalesce", [&] {
    const int run = runs.fetch_add(1);
    if (run == 0) {
      first_started.set_value();
      release.wait();
    } else if (run == 1) {
      second_started.set_value();
    }
  });
  thread.wake();
  ASSERT_EQ(first_started.get_future().wait_for(std::chrono::seconds(20)), std::future_status::ready);
  {
    const test::CountAllocations allocations;
    for (int i = 0; i < 1000; ++i) thread.wake();  // the job is still running: these return at once
    EXPECT_EQ(allocations.count(), 0u);
  }
  release_promise.set_value();
  ASSERT_EQ(second_started.get_future().wait_for(std::chrono::seconds(20)), std::future_status::ready);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(runs.load(), 2) << "1000 asks during one run make one more run";
}

}  // namespace
}  // namespace skinstream::server
