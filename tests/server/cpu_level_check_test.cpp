// The start-up CPU check is compiled in with the level the build was configured for (a CMake
// slip once left it checking nothing), and this CPU, which runs the tests, passes it.
#include "server/cpu_level_check.h"

#include <gtest/gtest.h>

#include <string>

namespace skinstream::server {
namespace {

TEST(CpuLevelCheck, RequiresTheLevelTheBuildWasConfiguredFor) {
  EXPECT_EQ(std::string(required_cpu_level()), std::string(SKINSTREAM_EXPECTED_CPU_LEVEL));
}

TEST(CpuLevelCheck, ThisCpuMeetsIt) {
  // Were it older, this program would have exited before main; the check must agree.
  EXPECT_TRUE(cpu_meets_required_level()) << required_cpu_level();
}

}  // namespace
}  // namespace skinstream::server
