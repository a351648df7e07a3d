#include "clients/bench/child_command.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

namespace skinstream::bench {
namespace {

TEST(ChildCommand, GivesWhatTheProgramPrintedOnBothStreamsAndHowItEnded) {
  const CommandResult result = run_command({"sh", "-c", "echo out; echo err >&2; exit 3"});
  EXPECT_EQ(result.exit_code, 3);
  EXPECT_FALSE(result.timed_out);
  EXPECT_EQ(result.output, "out\nerr\n");
}

TEST(ChildCommand, RunsAtTheNiceLevelAsked) {
  EXPECT_EQ(run_command({"nice"}, {.nice = 19}).output, "19\n");
  // Unasked, at this process's own (whatever the test was started at).
  EXPECT_EQ(run_command({"nice"}).output, std::to_string(getpriority(PRIO_PROCESS, 0)) + "\n");
}

TEST(ChildCommand, AProgramOverItsLimitIsKilled) {
  const auto start = std::chrono::steady_clock::now();
  const CommandResult result =
      run_command({"sh", "-c", "echo started; exec sleep 30"}, {.limit = std::chrono::milliseconds(300)});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_TRUE(result.timed_out);
  EXPECT_EQ(result.exit_code, -1);
  EXPECT_EQ(result.output, "started\n");
}

TEST(ChildCommand, AProgramNotFoundExits127SayingSo) {
  const CommandResult result = run_command({"skinstream-no-such-program"});
  EXPECT_EQ(result.exit_code, 127);
  EXPECT_EQ(result.output, "skinstream-no-such-program: not found\n");
}

}  // namespace
}  // namespace skinstream::bench
