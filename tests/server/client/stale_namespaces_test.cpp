// Left-over namespaces are told by the process in their name: a name whose process is gone is
// left over; a running process's, a name with no process id, or another prefix's are not.
#include "server/client/stale_namespaces.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "support/test_data.h"

namespace skinstream::server {
namespace {

pid_t pid_of_a_finished_process() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);  // reaped: nothing runs under that id now
  return child;
}

TEST(StaleNamespaces, OnlyNamesOfProcessesThatAreGoneAreLeftOver) {
  const std::filesystem::path dir = test::scratch_path("netns_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string dead = std::to_string(pid_of_a_finished_process()), alive = std::to_string(getpid());
  for (const std::string& name : std::vector<std::string>{"skmc" + dead + "-lan", "skmc" + dead + "-h0", "skmc" + alive + "-lan", "skmc-lan", "skmcx1",
                                  "skbench" + dead, "skmc"})
    std::ofstream(dir / name).put('\n');
  std::vector<std::string> found = namespaces_of_dead_processes("skmc", dir.string());
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, (std::vector<std::string>{"skmc" + dead + "-h0", "skmc" + dead + "-lan"}));
  EXPECT_EQ(namespaces_of_dead_processes("skbench", dir.string()), std::vector<std::string>{"skbench" + dead});
  EXPECT_TRUE(namespaces_of_dead_processes("skmc", (dir / "absent").string()).empty());  // no folder: nothing made yet
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace skinstream::server
