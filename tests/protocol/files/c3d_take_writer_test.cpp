// The take writer against the project's own C3D reader: what was committed reads back exactly,
// what was not is invisible until recovered, and a crash between the frames and the count they
// need loses nothing recover_c3d_take() can count.
#include "protocol/files/c3d_take_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "protocol/files/c3d.h"
#include "protocol/files/c3d_preamble.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

const std::vector<std::string> kLabels{"LFHD", "RFHD", "*1"};

std::vector<Vec3> frame_of(int i) {
  // Values a float holds exactly, and a missing sample on every third frame.
  std::vector<Vec3> points{Vec3(i + 0.5, -2.25 * i, 1000.0 + i), Vec3(-i, 0.125, 3.0), missing_point()};
  if (i % 3 == 0) points[1] = missing_point();
  return points;
}

void expect_frames(const Capture& capture, int count) {
  ASSERT_EQ(capture.frame_count, count);
  ASSERT_EQ(capture.labels, kLabels);
  for (int f = 0; f < count; ++f) {
    const std::vector<Vec3> expected = frame_of(f);
    for (int p = 0; p < 3; ++p) {
      EXPECT_EQ(capture.present(f, p), is_present(expected[p])) << "frame " << f << " point " << p;
      if (is_present(expected[p])) {
        EXPECT_EQ(capture.at(f, p), expected[p]) << "frame " << f << " point " << p;
      }
    }
  }
}

// What the writer leaves on disk when it dies after syncing frames but before the count.
void say_count(const std::string& path, uint64_t frames) {
  const std::vector<uint8_t> preamble =
      c3d_preamble(C3dPointLayout{kLabels, 120.0, 1, frames}, path, {}, -1.0f);
  std::string bytes = test::read_bytes(path);
  std::copy(preamble.begin(), preamble.end(), bytes.begin());
  test::write_bytes(path, bytes);
}

TEST(C3dTakeWriter, RefusesAFileThatExists) {
  const std::string path = test::scratch_path("take_exists.c3d");
  test::write_bytes(path, "keep me");
  EXPECT_TRUE(
      test::throws_file_error([&] { C3dTakeWriter writer(path, kLabels, 120.0); }, path, "cannot create"));
  EXPECT_EQ(test::read_bytes(path), "keep me");
}

TEST(C3dTakeWriter, AnEmptyTakeIsAValidFileOfNoFrames) {
  const std::string path = test::scratch_path("take_empty.c3d");
  C3dTakeWriter writer(path, kLabels, 120.0);
  const Capture capture = read_c3d(path);
  EXPECT_EQ(capture.frame_count, 0);
  EXPECT_EQ(capture.labels, kLabels);
  EXPECT_EQ(capture.rate_hz, 120.0);
}

TEST(C3dTakeWriter, CommittedFramesReadBackExactlyAndQueuedOnesAreNotSeen) {
  const std::string path = test::scratch_path("take_commit.c3d");
  C3dTakeWriter writer(path, kLabels, 120.0);
  for (int f = 0; f < 5; ++f) writer.append(frame_of(f));
  writer.commit();
  for (int f = 5; f < 8; ++f) writer.append(frame_of(f));
  EXPECT_EQ(writer.frames_committed(), 5u);
  EXPECT_EQ(writer.frames_queued(), 8u);
  expect_frames(read_c3d(path), 5);  // while the writer is still open
  writer.close();
  expect_frames(read_c3d(path), 8);
  EXPECT_EQ(std::filesystem::file_size(path) % 512, 0u);
}

TEST(C3dTakeWriter, RecoveryCountsTheFramesWrittenBeforeACrashAndDropsAPartialOne) {
  const std::string path = test::scratch_path("take_crash.c3d");
  {
    C3dTakeWriter writer(path, kLabels, 120.0);
    for (int f = 0; f < 7; ++f) writer.append(frame_of(f));
    writer.commit();
  }                    // not closed: as after kill -9
  say_count(path, 4);  // the frames reached the disk, the count did not
  test::write_bytes(path, test::read_bytes(path) + std::string(20, '\x7f'));  // half a frame
  expect_frames(read_c3d(path), 4);
  EXPECT_EQ(recover_c3d_take(path, kLabels, 120.0), 7u);
  expect_frames(read_c3d(path), 7);
  EXPECT_EQ(std::filesystem::file_size(path) % 512, 0u);
  // Recovering a closed take again changes nothing: the padding is not a frame.
  EXPECT_EQ(recover_c3d_take(path, kLabels, 120.0), 7u);
  expect_frames(read_c3d(path), 7);
}

TEST(C3dTakeWriter, RecoveryRefusesAFileOfOtherPoints) {
  const std::string path = test::scratch_path("take_other.c3d");
  { C3dTakeWriter writer(path, kLabels, 120.0); }
  const std::vector<std::string> other{"A", "B"};
  EXPECT_TRUE(
      test::throws_file_error([&] { recover_c3d_take(path, other, 120.0); }, path, "not a take file"));
  expect_frames(read_c3d(path), 0);
}

TEST(C3dTakeWriter, TakesLongerThanSixteenBitsOfFramesReadBack) {
  const std::string path = test::scratch_path("take_long.c3d");
  const std::vector<std::string> one{"M"};
  C3dTakeWriter writer(path, one, 120.0);
  const int frames = 70000;  // beyond POINT:FRAMES' 65535: the TRIAL fields carry the count
  for (int f = 0; f < frames; ++f) {
    const Vec3 p(f, 1.0, 2.0);
    writer.append(std::span<const Vec3>(&p, 1));
    if (f % 10000 == 0) writer.commit();
  }
  writer.close();
  const Capture capture = read_c3d(path);
  ASSERT_EQ(capture.frame_count, frames);
  EXPECT_EQ(capture.at(frames - 1, 0).x(), frames - 1);
  EXPECT_EQ(capture.at(12345, 0).x(), 12345);
}

}  // namespace
}  // namespace skinstream
