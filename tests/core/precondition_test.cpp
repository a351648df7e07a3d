#include "core/precondition.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace skinstream {
namespace {

constexpr Precondition require{"part joints"};

TEST(Precondition, FailureThrowsInvalidArgumentNamingTheComponent) {
  try {
    require(false, "marker " + std::to_string(3) + " is not finite");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "part joints: marker 3 is not finite");
  }
}

TEST(Precondition, PassesWhenTheConditionHolds) { EXPECT_NO_THROW(require(true, "no markers")); }

}  // namespace
}  // namespace skinstream
