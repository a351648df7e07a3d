// A take's per-frame table: lines reach the file only on commit, a killed writer's partial last
// line is cut, and the header is not counted as a frame.
#include "server/record/frame_table.h"

#include <gtest/gtest.h>

#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream::server {
namespace {

TEST(FrameTable, LinesReachTheFileOnCommit) {
  const std::string path = test::scratch_path("table_commit.tsv");
  FrameTable table(path, "a\tb");
  table.line() += "1\t2\n";
  EXPECT_EQ(test::read_bytes(path), "");
  table.commit();
  EXPECT_EQ(test::read_bytes(path), "a\tb\n1\t2\n");
  table.line() += "3\t4\n";
  table.close();
  EXPECT_EQ(test::read_bytes(path), "a\tb\n1\t2\n3\t4\n");
}

TEST(FrameTable, RefusesAFileThatExists) {
  const std::string path = test::scratch_path("table_exists.tsv");
  test::write_bytes(path, "keep");
  EXPECT_TRUE(test::throws_file_error([&] { FrameTable table(path, "h"); }, path, "cannot create"));
  EXPECT_EQ(test::read_bytes(path), "keep");
}

TEST(FrameTable, RecoveryCutsAPartialLineAndCountsFrames) {
  const std::string path = test::scratch_path("table_recover.tsv");
  test::write_bytes(path, "h\n1\n2\n3\t4");
  EXPECT_EQ(recover_frame_table(path), 2u);
  EXPECT_EQ(test::read_bytes(path), "h\n1\n2\n");
  EXPECT_EQ(recover_frame_table(path), 2u);
  test::write_bytes(path, "partial header");
  EXPECT_EQ(recover_frame_table(path), 0u);
  EXPECT_EQ(test::read_bytes(path), "");
}

}  // namespace
}  // namespace skinstream::server
