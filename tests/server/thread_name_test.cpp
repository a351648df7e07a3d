// Thread names as `top -H` shows them: set on the thread itself, cut at the kernel's 15
// characters rather than refused.
#include "server/thread_name.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>

namespace skinstream::server {
namespace {

// Names a new thread `name` and returns the name the OS then gives for it ("refused" when
// naming failed).
std::string name_read_back(const std::string& name) {
  std::string seen;
  std::thread([&] { seen = name_this_thread(name) ? this_thread_name() : "refused"; }).join();
  return seen;
}

TEST(ThreadName, ANamedThreadReadsItsNameBack) { EXPECT_EQ(name_read_back("pipeline"), "pipeline"); }

TEST(ThreadName, ALongNameIsCutToFifteenCharacters) {
  EXPECT_EQ(name_read_back("publish-0123456789"), "publish-0123456");
}

}  // namespace
}  // namespace skinstream::server
