#include "protocol/files/trc.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "protocol/files/c3d.h"
#include "protocol/files/file_error.h"
#include "support/capture_assertions.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::scratch_path;

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = scratch_path(name);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  return path;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

using test::throws_file_error;


const std::string kHeader =
    "PathFileType\t4\t(X/Y/Z)\twalk.trc\n"
    "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n";
const std::string kNames =
    "Frame#\tTime\tRASI\t\t\tLASI\t\t\t\n"
    "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\t\n"
    "\n";
// A small hand-written file in metres: trailing tabs, a missing marker as empty cells.
const std::string kRows =
    "7\t0\t1\t2\t3\t0.5\t0.25\t0.125\t\n"
    "8\t0.01\t1.5\t2\t3\t\t\t\t\n"
    "9\t0.02\t1\t2\t3.5\t0.5\t0.25\t-0.125\n";

std::string small_trc(const std::string& values_line, const std::string& rows = kRows) {
  return kHeader + values_line + "\n" + kNames + rows;
}
const std::string kValues = "100\t100\t3\t2\tm\t100\t7\t3";

// ---------------------------------------------------------------- invalid input

TEST(TrcInvalid, MissingFile) {
  const std::string path = scratch_path("no_such_markers.trc");
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "no such file"));
}

TEST(TrcInvalid, NotATrcFile) {
  const std::string path = write_text("trc_not.trc", "hello\tworld\n");
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "not a TRC file"));
}

TEST(TrcInvalid, NonNumericCell) {
  std::string rows = kRows;
  rows.replace(rows.find("1.5"), 3, "abc");
  const std::string path = write_text("trc_non_numeric.trc", small_trc(kValues, rows));
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "line 8, column 3: 'abc' is not a number"));
  const std::string bad_rate =
      write_text("trc_bad_rate_text.trc", small_trc("fast\t100\t3\t2\tm\t100\t7\t3"));
  EXPECT_TRUE(throws_file_error([&] { read_trc(bad_rate); }, bad_rate, "line 3, column 1"));
}

TEST(TrcInvalid, WrongColumnCount) {
  const std::string fewer = write_text(
      "trc_fewer.trc",
      small_trc(kValues, "7\t0\t1\t2\t3\t0.5\t0.25\n8\t0.01\t1\t2\t3\t1\t2\t3\n9\t0.02\t1\t2\t3\t1\t2\t3\n"));
  EXPECT_TRUE(throws_file_error([&] { read_trc(fewer); }, fewer, "line 7: 7 columns, expected 8"));
  std::string text = small_trc(kValues);
  text.replace(text.find("-0.125"), 6, "-0.125\t4");
  const std::string extra = write_text("trc_extra.trc", text);
  EXPECT_TRUE(throws_file_error([&] { read_trc(extra); }, extra, "line 9: 9 columns, expected 8"));
}

TEST(TrcInvalid, PartialCoordinates) {
  std::string rows = kRows;
  rows.replace(rows.find("0.5\t0.25\t0.125"), 14, "0.5\t\t0.125");
  const std::string path = write_text("trc_partial.trc", small_trc(kValues, rows));
  EXPECT_TRUE(
      throws_file_error([&] { read_trc(path); }, path, "line 7: marker 2 has only some of its coordinates"));
}

TEST(TrcInvalid, TruncatedCopies) {
  const std::string text = small_trc(kValues);
  // Cut inside the header, inside a row and inside the last number: never a silent short capture.
  for (size_t size :
       {size_t{0}, size_t{10}, kHeader.size() + 5, text.size() - 30, text.size() - 10, text.size() - 3}) {
    SCOPED_TRACE(size);
    const std::string path = write_text("trc_truncated.trc", text.substr(0, size));
    EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, ""));
  }
  // "-0.125" cut to "-0.1" still parses: only the missing line end gives the cut away.
  const std::string cut_number = write_text("trc_cut_number.trc", text.substr(0, text.size() - 3));
  EXPECT_TRUE(
      throws_file_error([&] { read_trc(cut_number); }, cut_number, "truncated: line 9 has no line end"));
  const std::string rows_missing = write_text("trc_rows_missing.trc", text.substr(0, text.find("9\t0.02")));
  EXPECT_TRUE(throws_file_error([&] { read_trc(rows_missing); }, rows_missing,
                                "truncated: NumFrames says 3, file holds 2 rows"));
  const std::string header_only = write_text("trc_header_only.trc", kHeader);
  EXPECT_TRUE(throws_file_error([&] { read_trc(header_only); }, header_only, "truncated"));
}

TEST(TrcInvalid, MoreRowsThanNumFrames) {
  const std::string path =
      write_text("trc_more_rows.trc", small_trc(kValues, kRows + "10\t0.03\t1\t2\t3\t1\t2\t3\n"));
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "NumFrames says 3, file holds 4 rows"));
}

TEST(TrcInvalid, ZeroOrNegativeRate) {
  for (const std::string rate : {"0", "-100"}) {
    const std::string path = write_text("trc_rate.trc", small_trc(rate + "\t100\t3\t2\tm\t100\t7\t3"));
    EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "bad DataRate " + rate));
  }
}

TEST(TrcInvalid, MarkerCountMismatch) {
  const std::string path = write_text("trc_markers.trc", small_trc("100\t100\t3\t3\tm\t100\t7\t3"));
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "6 coordinate columns for NumMarkers 3"));
  std::string names =
      small_trc("100\t100\t3\t1\tm\t100\t7\t3", "7\t0\t1\t2\t3\n8\t0\t1\t2\t3\n9\t0\t1\t2\t3\n");
  names.replace(names.find("X2\tY2\tZ2\t"), 9, "");
  const std::string extra_name = write_text("trc_extra_name.trc", names);
  EXPECT_TRUE(throws_file_error([&] { read_trc(extra_name); }, extra_name, "marker name 'LASI'"));
}

// A name with a terminal escape and a line break, a megabyte long: the error names it escaped and cut.
TEST(TrcInvalid, HostileMarkerNameStaysOnePrintableLine) {
  std::string names =
      small_trc("100\t100\t3\t1\tm\t100\t7\t3", "7\t0\t1\t2\t3\n8\t0\t1\t2\t3\n9\t0\t1\t2\t3\n");
  names.replace(names.find("X2\tY2\tZ2\t"), 9, "");
  names.replace(names.find("LASI"), 4, "\x1b[31m\r" + std::string(1 << 20, 'L'));
  const std::string path = write_text("trc_hostile_name.trc", names);
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "marker name '\\x1b[31m\\x0dLLLL"));
  try {
    read_trc(path);
  } catch (const FileError& e) {
    EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
  }
}

TEST(TrcInvalid, UnknownUnitsAndMissingKeys) {
  const std::string feet = write_text("trc_feet.trc", small_trc("100\t100\t3\t2\tft\t100\t7\t3"));
  EXPECT_TRUE(throws_file_error([&] { read_trc(feet); }, feet, "unknown Units 'ft'"));
  std::string text = small_trc(kValues);
  text.replace(text.find("NumFrames"), 9, "Frames");
  const std::string no_frames = write_text("trc_no_frames.trc", text);
  EXPECT_TRUE(throws_file_error([&] { read_trc(no_frames); }, no_frames, "no NumFrames"));
}

TEST(TrcInvalid, FrameNumbersMustBeConsecutive) {
  std::string rows = kRows;
  rows.replace(rows.find("9\t0.02"), 1, "12");
  const std::string path = write_text("trc_frames.trc", small_trc(kValues, rows));
  EXPECT_TRUE(throws_file_error([&] { read_trc(path); }, path, "line 9: frame number 12, expected 9"));
}

// ---------------------------------------------------------------- reading and writing

TEST(TrcRead, HandWrittenFileInMetres) {
  const Capture c = read_trc(write_text("trc_small.trc", small_trc(kValues)));
  EXPECT_EQ(c.labels, (std::vector<std::string>{"RASI", "LASI"}));
  EXPECT_EQ(c.frame_count, 3);
  EXPECT_EQ(c.first_frame, 7);
  EXPECT_DOUBLE_EQ(c.rate_hz, 100.0);
  EXPECT_EQ(c.at(0, 0), Vec3(1000, 2000, 3000));
  EXPECT_EQ(c.at(0, 1), Vec3(500, 250, 125));
  EXPECT_EQ(c.at(1, 0), Vec3(1500, 2000, 3000));
  EXPECT_FALSE(c.present(1, 1));
  EXPECT_EQ(c.at(2, 1), Vec3(500, 250, -125));
}

TEST(TrcRead, CentimetresAndWindowsLineEnds) {
  std::string text = small_trc("100\t100\t3\t2\tcm\t100\t7\t3");
  std::string crlf;
  for (char ch : text) crlf += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
  const Capture c = read_trc(write_text("trc_cm.trc", crlf));
  EXPECT_EQ(c.at(0, 0), Vec3(10, 20, 30));
  EXPECT_EQ(c.labels[1], "LASI");
}

TEST(TrcFromMemory, ReadsAsTheFileReaderDoes) {
  const Capture c = read_c3d(test::shared_path("data/captures/cmu/85_02.c3d"));
  const std::string path = scratch_path("trc_cmu_memory.trc");
  write_trc(c, path);
  test::expect_same_capture(read_trc(path), read_trc_bytes(read_text(path), "cmu.trc"));
  const std::string small = small_trc(kValues);
  test::expect_same_capture(read_trc(write_text("trc_small_memory.trc", small)), read_trc_bytes(small, "small.trc"));
}

TEST(TrcFromMemory, RefusesUnderTheGivenName) {
  const std::string text = small_trc(kValues);
  EXPECT_TRUE(throws_file_error([&] { read_trc_bytes(text.substr(0, text.size() - 3), "walk.trc"); }, "walk.trc",
                                "truncated: line 9 has no line end"));
  EXPECT_TRUE(throws_file_error([&] { read_trc_bytes("", "empty.trc"); }, "empty.trc", "truncated: file ends at line 0"));
}

TEST(TrcWrite, HeaderLines) {
  Capture c({"A", "B"}, 2, 60.0);
  c.first_frame = 1;
  c.at(0, 0) = Vec3(1, 2, 3);
  c.at(1, 1) = Vec3(4.5, -5, 6);
  const std::string path = scratch_path("trc_written.trc");
  write_trc(c, path);
  std::istringstream lines(read_text(path));
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "PathFileType\t4\t(X/Y/Z)\ttrc_written.trc");
  std::getline(lines, line);
  EXPECT_EQ(
      line,
      "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames");
  std::getline(lines, line);
  EXPECT_EQ(line, "60\t60\t2\t2\tmm\t60\t1\t2");
  std::getline(lines, line);
  EXPECT_EQ(line, "Frame#\tTime\tA\t\t\tB\t\t");
  std::getline(lines, line);
  EXPECT_EQ(line, "\t\tX1\tY1\tZ1\tX2\tY2\tZ2");
  std::getline(lines, line);
  EXPECT_EQ(line, "");
  std::getline(lines, line);
  EXPECT_EQ(line, "1\t0\t1\t2\t3\t\t\t");
  std::getline(lines, line);
  EXPECT_EQ(line, "2\t0.016666666666666666\t\t\t\t4.5\t-5\t6");
}

TEST(TrcWrite, RoundTripIsExactWithGapsAndUnlabelledChannels) {
  Capture c({"LFHD", "", "*3", "RTOE"}, 40, 59.94);
  c.first_frame = 0;
  for (int f = 0; f < c.frame_count; ++f)
    for (int p = 0; p < c.point_count(); ++p)
      c.at(f, p) = Vec3(f * 0.1 + p, -1.0 / (f + 1), 1e-7 * p + 1234.5678901234);
  for (int f = 0; f < 5; ++f) c.at(f, 0) = missing_point();    // gap at the start
  for (int f = 10; f < 20; ++f) c.at(f, 2) = missing_point();  // in the middle
  c.at(39, 3) = missing_point();                               // at the end
  const std::string path = scratch_path("trc_round_trip.trc");
  write_trc(c, path);
  test::expect_same_capture(c, read_trc(path));
}

TEST(TrcWrite, RealCaptureRoundTripsExactly) {
  const Capture c = read_c3d(test::shared_path("data/captures/cmu/85_02.c3d"));
  const std::string path = scratch_path("trc_cmu.trc");
  write_trc(c, path);
  test::expect_same_capture(c, read_trc(path));
}

TEST(TrcWrite, C3dToTrcToC3dKeepsGaps) {
  const Capture original =
      read_c3d(test::shared_path("data/captures/kineticstoolkit/kinematics_basket_sprint.c3d"));
  const std::string trc = scratch_path("trc_basket.trc");
  write_trc(original, trc);
  const Capture via_trc = read_trc(trc);
  test::expect_same_capture(original, via_trc);
  const std::string c3d = scratch_path("trc_basket_back.c3d");
  write_c3d(via_trc, c3d);
  test::expect_same_capture(original, read_c3d(c3d));
}

TEST(TrcWrite, RefusesWhatTrcCannotHold) {
  const std::string path = scratch_path("trc_refused.trc");
  Capture tabbed({"a\tb"}, 1, 100.0);
  EXPECT_TRUE(throws_file_error([&] { write_trc(tabbed, path); }, path, "tab or line break"));
  Capture no_rate({"a"}, 1, -1.0);
  EXPECT_TRUE(throws_file_error([&] { write_trc(no_rate, path); }, path, "frame rate"));
  const std::string no_folder = scratch_path("no_such_folder/x.trc");
  EXPECT_TRUE(
      throws_file_error([&] { write_trc(Capture({"a"}, 1, 100.0), no_folder); }, no_folder, "cannot open"));
}

}  // namespace
}  // namespace skinstream
