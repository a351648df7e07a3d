#include "server/pipeline/deform_cpus.h"

#include <gtest/gtest.h>

#include <sched.h>

#include <algorithm>
#include <stdexcept>

namespace skinstream::server {
namespace {

std::string error_of(const std::string& spec, int threads, const std::vector<int>& allowed) {
  try {
    choose_deform_cpus(spec, threads, allowed);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(DeformCpus, AutoTakesTheLastAllowedCpusWhenThereIsOnePerThread) {
  EXPECT_EQ(choose_deform_cpus("auto", 2, {0, 1, 2}), (std::vector<int>{1, 2}));
  EXPECT_EQ(choose_deform_cpus("auto", 2, {0, 1, 2, 5}), (std::vector<int>{2, 5}));
  EXPECT_EQ(choose_deform_cpus("auto", 1, {0, 1, 2, 3}), (std::vector<int>{3}));
  EXPECT_EQ(choose_deform_cpus("auto", 2, {0, 1}), (std::vector<int>{0, 1}));  // the io thread shares them
  EXPECT_TRUE(choose_deform_cpus("auto", 3, {0, 1}).empty());  // sharing a CPU would be worse than the OS's choice
  EXPECT_TRUE(choose_deform_cpus("auto", 2, {}).empty());
  EXPECT_TRUE(choose_deform_cpus("off", 2, {0, 1, 2, 3}).empty());
}

TEST(DeformCpus, AListGivesOneAllowedCpuPerThreadInOrder) {
  EXPECT_EQ(choose_deform_cpus("3,1", 2, {0, 1, 2, 3}), (std::vector<int>{3, 1}));
  EXPECT_NE(error_of("3", 2, {0, 1, 2, 3}).find("names 1 CPUs for 2 deform threads"), std::string::npos);
  EXPECT_NE(error_of("1,7", 2, {0, 1, 2, 3}).find("CPU 7 is not one this process may run on"), std::string::npos);
}

TEST(DeformCpus, MalformedSettingsSayWhatIsAccepted) {
  for (const char* bad : {"", "a", "1,", ",1", "1,,2", "-1", "1 2", "Auto", "12345"}) {
    EXPECT_NE(deform_cpus_problem(bad).find("\"auto\", \"off\" or CPU numbers"), std::string::npos) << bad;
    EXPECT_FALSE(error_of(bad, 1, {0, 1}).empty()) << bad;
  }
  EXPECT_NE(deform_cpus_problem("2,0,2").find("twice"), std::string::npos);
  EXPECT_EQ(deform_cpus_problem("0,1"), "");
}

TEST(DeformCpus, TheProcessMayRunOnSomeCpuAndAThreadCanBePinnedThere) {
  const std::vector<int> allowed = allowed_cpus();
  ASSERT_FALSE(allowed.empty());
  EXPECT_TRUE(std::is_sorted(allowed.begin(), allowed.end()));
  EXPECT_TRUE(pin_this_thread(allowed.back()));
  EXPECT_EQ(sched_getcpu(), allowed.back());  // moved there before the call returned
  EXPECT_FALSE(pin_this_thread(-1));
  EXPECT_FALSE(set_this_thread_cpus({}));
  EXPECT_TRUE(set_this_thread_cpus(allowed));  // the test thread as it was
}

}  // namespace
}  // namespace skinstream::server
