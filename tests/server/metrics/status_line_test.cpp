// The status line reads the interval since the previous one: its frames, rate and p99, not the
// daemon's whole life.
#include "server/metrics/status_line.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

TEST(StatusLine, ReportsTheIntervalSinceThePreviousLine) {
  Metrics metrics;
  StatusLine status;
  const auto start = StatusLine::Clock::now();
  // A slow first interval: 10 frames at 20 ms.
  for (int i = 0; i < 10; ++i) metrics.receive_to_publish.observe_ns(20'000'000);
  metrics.frames_received = 10;
  metrics.frames_published = 10;
  status.next("Actor1", metrics, 0, 0, start);

  // Then 600 frames in 5 s at 0.4 ms, 2 given way, 3 dropped for subscribers.
  for (int i = 0; i < 600; ++i) metrics.receive_to_publish.observe_ns(400'000);
  metrics.frames_received = 612;
  metrics.frames_published = 610;
  metrics.frames_dropped = 2;
  const std::string line = status.next("Actor1", metrics, 4, 3, start + std::chrono::seconds(5));
  EXPECT_EQ(line,
            "status Actor1: 602 frames in, 600 out (120.0/s) in 5 s; processing p99 <= 0.50 ms; 4 subscribers; dropped 2 in the "
            "pipeline, 3 for subscribers")
      << line;

  // A subscriber with drops left: its count went with it, and no new drops are claimed.
  const std::string after = status.next("Actor1", metrics, 3, 1, start + std::chrono::seconds(10));
  EXPECT_NE(after.find("0 for subscribers"), std::string::npos) << after;
  EXPECT_NE(after.find("0 out (0.0/s)"), std::string::npos) << after;
  EXPECT_NE(after.find("p99 <= 0.00 ms"), std::string::npos) << after;
}

}  // namespace
}  // namespace skinstream::server
