// skinstream convert, run in-process on a real capture: C3D to TRC and back keeps every sample.
#include "clients/skinstream/cmd_convert.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "protocol/files/capture_file.h"
#include "support/capture_assertions.h"
#include "support/cli_run.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"
#include "tests/clients/skinstream/command_output.h"

namespace skinstream {
namespace {

using test::kCmu02;

TEST(ConvertCommand, C3dToTrcAndBackKeepsEverySample) {
  const Capture original = read_capture(kCmu02);
  cli::ConvertOptions to_trc{kCmu02, test::scratch_path("convert_85_02.trc")};
  const test::CommandOutput first = test::run_command(cli::run_convert, to_trc);
  EXPECT_EQ(first.exit_code, 0);
  EXPECT_EQ(first.text, "wrote " + to_trc.out_path + ": " + std::to_string(original.point_count()) + " channels, " +
                            std::to_string(original.frame_count) + " frames\n");

  cli::ConvertOptions back{to_trc.out_path, test::scratch_path("convert_85_02_back.c3d")};
  ASSERT_EQ(test::run_command(cli::run_convert, back).exit_code, 0);
  // TRC holds millimetres as text: equal to a micrometre.
  test::expect_same_capture(original, read_capture(back.out_path), 1e-3);
}

TEST(ConvertCommand, AMissingInputIsAFileErrorAndWritesNothing) {
  const cli::ConvertOptions o{test::scratch_path("absent.c3d"), test::scratch_path("never_written.trc")};
  EXPECT_TRUE(test::throws_file_error([&] { test::run_command(cli::run_convert, o); }, o.in_path, ""));
  EXPECT_FALSE(std::filesystem::exists(o.out_path));
}

}  // namespace
}  // namespace skinstream
