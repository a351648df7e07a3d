// The rate-limited log: one line per category a second, at warning or info level, and nothing
// counted or printed at a level the log does not show.
#include "server/logging.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>
#include <thread>

namespace skinstream::server {
namespace {

// spdlog's default logger writing into a string for the test's life, at level info.
class CapturedLog {
 public:
  CapturedLog() : previous_(spdlog::default_logger()) {
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("captured", std::make_shared<spdlog::sinks::ostream_sink_st>(out_)));
    spdlog::set_pattern("%l %v");
    set_log_level("info");
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  std::string text() const { return out_.str(); }

 private:
  std::ostringstream out_;
  std::shared_ptr<spdlog::logger> previous_;
};

TEST(RateLimitedLog, InfoLinesOfOneCategoryComeOnceASecondWithTheCountSuppressed) {
  const CapturedLog log;
  RateLimitedLog limited(std::chrono::milliseconds(200));
  EXPECT_TRUE(limited.info("subscriber_hello", "subscriber 1"));
  for (int i = 2; i <= 300; ++i) EXPECT_FALSE(limited.info("subscriber_hello", "subscriber " + std::to_string(i)));
  EXPECT_TRUE(limited.info("subscriber_gone", "subscriber 1 gone")) << "another category has its own limit";
  std::this_thread::sleep_for(std::chrono::milliseconds(250));
  EXPECT_TRUE(limited.info("subscriber_hello", "subscriber 301"));
  EXPECT_EQ(log.text(),
            "info subscriber_hello: subscriber 1\n"
            "info subscriber_gone: subscriber 1 gone\n"
            "info subscriber_hello: subscriber 301 (299 more like it in the last second)\n");
}

TEST(RateLimitedLog, NothingIsCountedAtALevelTheLogDoesNotShow) {
  const CapturedLog log;
  set_log_level("warn");
  RateLimitedLog limited(std::chrono::milliseconds(200));
  EXPECT_FALSE(limited.info("subscriber_hello", "subscriber 1"));
  EXPECT_TRUE(limited.warn("subscriber_refused", "subscriber 2: refused"));
  set_log_level("info");
  EXPECT_TRUE(limited.info("subscriber_hello", "subscriber 3")) << "the line not shown did not start the category's second";
  EXPECT_EQ(log.text(), "warning subscriber_refused: subscriber 2: refused\ninfo subscriber_hello: subscriber 3\n");
}

}  // namespace
}  // namespace skinstream::server
