#include "server/file_naming.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

TEST(FileNaming, ASubjectsNameBecomesAFileStemThatIsNeverHiddenNorLong) {
  EXPECT_EQ(file_stem_of("Actor1"), "Actor1");
  EXPECT_EQ(file_stem_of("Actor 1/a"), "Actor_1_a");
  EXPECT_EQ(file_stem_of("../etc"), "s.._etc");
  EXPECT_EQ(file_stem_of(""), "s");
  EXPECT_EQ(file_stem_of(std::string(100, 'x')).size(), 64u);
}

TEST(FileNaming, TimesAreWrittenInUtc) {
  const auto when =
      std::chrono::system_clock::time_point(std::chrono::seconds(1'796'545'923));  // 2026-12-06T08:32:03Z
  EXPECT_EQ(iso_utc(when), "2026-12-06T08:32:03Z");
  EXPECT_EQ(utc_text(when, "take-%Y%m%d-%H%M%S"), "take-20261206-083203");
}

}  // namespace
}  // namespace skinstream::server
