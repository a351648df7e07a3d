// The replay servers' clock: frames on their deadlines, the end once (never with loop), and
// nothing after stop() or after the timeline is gone.
#include "server/replay/replay_timeline.h"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

namespace skinstream::server {
namespace {

using std::chrono::milliseconds;

TEST(ReplayTimeline, ProducesEveryFrameOnItsDeadlineThenFinishesOnce) {
  asio::io_context io;
  ReplayTimeline timeline(io, 100.0, 2.0, 5, false);  // 200 frames per second of wall time
  std::vector<uint64_t> frames;
  int finished = 0;
  timeline.set_on_frame([&](uint64_t k) { frames.push_back(k); });
  timeline.set_on_finished([&] { ++finished; });
  EXPECT_FALSE(timeline.started());
  const auto begin = std::chrono::steady_clock::now();
  timeline.start();
  timeline.start();  // a second request changes nothing
  io.run();
  EXPECT_GE(std::chrono::steady_clock::now() - begin, milliseconds(20));  // frame 4 at 4 / 200 s
  EXPECT_EQ(frames, (std::vector<uint64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(finished, 1);
  EXPECT_TRUE(timeline.finished());
  EXPECT_EQ(timeline.frames_produced(), 5u);
}

TEST(ReplayTimeline, LoopKeepsCountingAndNeverFinishes) {
  asio::io_context io;
  ReplayTimeline timeline(io, 1000.0, 1.0, 3, true);
  std::vector<uint64_t> frames;
  timeline.set_on_frame([&](uint64_t k) {
    frames.push_back(k);
    if (frames.size() == 7) timeline.stop();
  });
  timeline.set_on_finished([] { ADD_FAILURE() << "a looping timeline finished"; });
  timeline.start();
  io.run();
  EXPECT_EQ(frames, (std::vector<uint64_t>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_FALSE(timeline.finished());
}

TEST(ReplayTimeline, NothingToPlayNeverStarts) {
  asio::io_context io;
  ReplayTimeline empty(io, 100.0, 1.0, 0, false);
  ReplayTimeline no_rate(io, 0.0, 1.0, 10, false);
  empty.start();
  no_rate.start();
  EXPECT_FALSE(empty.started());
  EXPECT_FALSE(no_rate.started());
  EXPECT_EQ(io.poll(), 0u);
}

TEST(ReplayTimeline, StoppedBeforeStartingNeverStarts) {
  asio::io_context io;
  ReplayTimeline timeline(io, 100.0, 1.0, 10, false);
  timeline.set_on_frame([](uint64_t) { ADD_FAILURE() << "a frame after stop()"; });
  timeline.stop();
  timeline.start();
  EXPECT_FALSE(timeline.started());
  io.poll();
}

// Two timelines due at once, each destroying the other on its frame: the second one's handler
// is then already queued with success, and must return without touching the destroyed timeline.
TEST(ReplayTimeline, ATimelineDestroyedWithAFrameDueProducesNothing) {
  asio::io_context io;
  auto a = std::make_unique<ReplayTimeline>(io, 10.0, 1.0, 2, false);
  auto b = std::make_unique<ReplayTimeline>(io, 10.0, 1.0, 2, false);
  int frames = 0;
  a->set_on_frame([&](uint64_t) {
    ++frames;
    b.reset();
  });
  b->set_on_frame([&](uint64_t) {
    ++frames;
    a.reset();
  });
  a->start();
  b->start();
  std::this_thread::sleep_for(milliseconds(5));  // both first frames are due before the loop runs
  io.run_for(milliseconds(50));                  // the second frame is 100 ms away
  EXPECT_EQ(frames, 1);
  EXPECT_TRUE(a == nullptr || b == nullptr);
  a.reset();
  b.reset();
  io.run();
}

}  // namespace
}  // namespace skinstream::server
