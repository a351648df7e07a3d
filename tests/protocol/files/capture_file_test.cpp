#include "protocol/files/capture_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

#include "protocol/files/c3d.h"
#include "protocol/files/file_error.h"
#include "protocol/files/trc.h"
#include "support/capture_assertions.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::scratch_path;

const std::string kCmu = test::shared_path("data/captures/cmu/85_02.c3d");

std::string error_message(const std::function<void()>& call) {
  try {
    call();
  } catch (const FileError& e) {
    return e.what();
  }
  return "(no FileError)";
}


TEST(CaptureFileInvalid, MissingFile) {
  const std::string path = scratch_path("no_such_capture_file.c3d");
  EXPECT_EQ(error_message([&] { read_capture(path); }), path + ": no such file");
  const std::string trc = scratch_path("no_such_capture_file.trc");
  EXPECT_EQ(error_message([&] { read_capture(trc); }), trc + ": no such file");
}

TEST(CaptureFileInvalid, UnknownExtension) {
  const std::string bvh = scratch_path("walk.bvh");
  EXPECT_EQ(error_message([&] { read_capture(bvh); }),
            bvh + ": unknown capture file extension '.bvh' (expected .c3d or .trc)");
  const std::string bare = scratch_path("walk");
  EXPECT_EQ(error_message([&] { read_capture(bare); }), bare + ": no file extension (expected .c3d or .trc)");
  const std::string txt = scratch_path("capture_file_out.txt");
  std::filesystem::remove(txt);
  EXPECT_NE(error_message([&] { write_capture(Capture({"a"}, 1, 100.0), txt); }).find("'.txt'"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(txt));  // refused before anything is written
}

TEST(CaptureFile, DispatchesOnExtensionIgnoringCase) {
  const Capture direct = read_c3d(kCmu);
  test::expect_same_capture(direct, read_capture(kCmu));
  const std::string upper = scratch_path("capture_file_upper.C3D");
  std::filesystem::copy_file(kCmu, upper, std::filesystem::copy_options::overwrite_existing);
  test::expect_same_capture(direct, read_capture(upper));

  const std::string trc = scratch_path("capture_file_mixed.Trc");
  write_trc(direct, trc);
  test::expect_same_capture(direct, read_capture(trc));
}

TEST(CaptureFile, WritesEitherFormatByExtension) {
  const Capture c = read_c3d(test::shared_path("data/captures/c3d-org/sample02/pc_real.c3d"));
  for (const std::string name : {"capture_file_out.c3d", "capture_file_out.TRC"}) {
    SCOPED_TRACE(name);
    const std::string path = scratch_path(name);
    write_capture(c, path);
    test::expect_same_capture(c, read_capture(path));  // 7% of the samples are gaps
  }
  // The C3D really is a C3D and the TRC really is text.
  EXPECT_NO_THROW(read_c3d(scratch_path("capture_file_out.c3d")));
  EXPECT_NO_THROW(read_trc(scratch_path("capture_file_out.TRC")));
}

}  // namespace
}  // namespace skinstream
