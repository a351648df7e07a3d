#include "clients/bench/child_command.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <thread>

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

// SCHED_IDLE is policy 5 in /proc's view of the process.
TEST(ChildCommand, RunsUnderSchedIdleWhenAsked) {
  EXPECT_EQ(
      run_command({"sh", "-c", "grep -o 'policy.*' /proc/self/sched | tr -d ' '"}, {.idle = true}).output,
      "policy:5\n");
  EXPECT_EQ(run_command({"sh", "-c", "grep -o 'policy.*' /proc/self/sched | tr -d ' '"}).output,
            "policy:0\n");
}

// A joiner started beforehand waits on its standard input, a pipe the bench closes at the join.
TEST(ChildCommand, ReadsTheStandardInputItIsGiven) {
  int go[2];
  ASSERT_EQ(pipe2(go, O_CLOEXEC), 0);
  std::thread closer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_EQ(write(go[1], "ready", 5), 5);
    close(go[1]);
  });
  const CommandResult result = run_command({"cat"}, {.stdin_fd = go[0], .limit = std::chrono::seconds(20)});
  closer.join();
  close(go[0]);
  EXPECT_FALSE(result.timed_out);
  EXPECT_EQ(result.output, "ready");
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
