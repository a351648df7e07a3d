#include "server/publish/publish_threads.h"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <set>
#include <thread>

namespace skinstream::server {
namespace {

TEST(PublishThreads, WithNoThreadsEverySubscriberStaysOnTheFallback) {
  asio::io_context fallback;
  PublishThreads threads(0);
  threads.start();
  const PublishThreads::Placement placed = threads.place(fallback);
  EXPECT_EQ(&placed.io, &fallback);
  EXPECT_EQ(placed.token, nullptr);
}

TEST(PublishThreads, NewSubscribersGoToTheThreadWithTheFewestAndLeaveWithTheirToken) {
  asio::io_context fallback;
  PublishThreads threads(2);
  auto a = threads.place(fallback);
  auto b = threads.place(fallback);
  auto c = threads.place(fallback);
  EXPECT_NE(&a.io, &fallback);
  EXPECT_NE(&a.io, &b.io);  // one each, then the first again
  EXPECT_EQ(&c.io, &a.io);
  EXPECT_EQ(threads.subscribers_on(0), 2);
  EXPECT_EQ(threads.subscribers_on(1), 1);
  // The two on the first thread leave: it has the fewest now, so the next one goes there, and
  // on a tie the first thread wins again (the choice is by load, not round robin).
  a.token.reset();
  c.token.reset();
  EXPECT_EQ(threads.subscribers_on(0), 0);
  auto d = threads.place(fallback);
  EXPECT_NE(&d.io, &b.io);
  auto e = threads.place(fallback);
  EXPECT_EQ(&e.io, &d.io);
  EXPECT_EQ(threads.subscribers_on(0), 2);
  EXPECT_EQ(threads.subscribers_on(1), 1);
}

// Each context runs on a thread of its own, handlers posted before stop() run, and stop() ends
// the threads even with work pending (a timer that would never fire).
TEST(PublishThreads, EachContextRunsOnItsOwnThreadAndStopsAfterWhatWasPosted) {
  asio::io_context fallback;
  PublishThreads threads(2);
  threads.start();
  auto a = threads.place(fallback);
  auto b = threads.place(fallback);
  std::promise<std::thread::id> on_a, on_b;
  asio::post(a.io, [&] { on_a.set_value(std::this_thread::get_id()); });
  asio::post(b.io, [&] { on_b.set_value(std::this_thread::get_id()); });
  const std::thread::id id_a = on_a.get_future().get(), id_b = on_b.get_future().get();
  EXPECT_NE(id_a, id_b);
  EXPECT_NE(id_a, std::this_thread::get_id());

  asio::steady_timer never(a.io, std::chrono::hours(1));
  never.async_wait([](const boost::system::error_code&) {});
  std::atomic<int> ran_before_stop{0};
  asio::post(a.io, [&] { ran_before_stop.fetch_add(1); });
  asio::post(b.io, [&] { ran_before_stop.fetch_add(1); });
  threads.stop();
  threads.join();
  EXPECT_EQ(ran_before_stop.load(), 2);
}

}  // namespace
}  // namespace skinstream::server
