// Thread names as `top -H` shows them: set on the thread itself, cut at the kernel's 15
// characters rather than refused.
#include "server/thread_name.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>

namespace skinstream::server {
namespace {

TEST(ThreadName, ANamedThreadReadsItsNameBack) {
  std::string seen;
  bool named = false;
  std::thread([&] {
    named = name_this_thread("pipeline");
    seen = this_thread_name();
  }).join();
  EXPECT_TRUE(named);
  EXPECT_EQ(seen, "pipeline");
}

TEST(ThreadName, ALongNameIsCutToFifteenCharacters) {
  std::string seen;
  bool named = false;
  std::thread([&] {
    named = name_this_thread("publish-0123456789");
    seen = this_thread_name();
  }).join();
  EXPECT_TRUE(named);
  EXPECT_EQ(seen, "publish-0123456");
}

}  // namespace
}  // namespace skinstream::server
