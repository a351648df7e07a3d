#include "protocol/subject_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "core/offline/subject_builder.h"
#include "protocol/file_error.h"
#include "support/synthetic_limb.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void spit(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
std::string message_of(const std::string& path) {
  try {
    read_subject(path);
  } catch (const FileError& e) {
    return e.what();
  }
  return "";
}

class SubjectFile : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = build_subject(test::make_limb_capture(), {});
    path_ = test::scratch_path("limb.subject");
    write_subject(model_, path_);
  }
  SubjectModel model_;
  std::string path_;
};

TEST_F(SubjectFile, MissingFileIsAClearError) {
  EXPECT_NE(message_of(test::scratch_path("nope.subject")).find("cannot open"), std::string::npos);
}

TEST_F(SubjectFile, RejectsAnotherFormat) {
  const std::string other = test::scratch_path("other.subject");
  spit(other, std::vector<char>(100, 'x'));
  EXPECT_NE(message_of(other).find("bad magic"), std::string::npos);
}

TEST_F(SubjectFile, RejectsAnotherVersion) {
  std::vector<char> bytes = slurp(path_);
  bytes[8] = 99;  // version field
  const std::string other = test::scratch_path("v99.subject");
  spit(other, bytes);
  EXPECT_NE(message_of(other).find("version 99"), std::string::npos);
}

TEST_F(SubjectFile, RejectsATruncatedFile) {
  std::vector<char> bytes = slurp(path_);
  bytes.resize(bytes.size() / 2);
  const std::string cut = test::scratch_path("cut.subject");
  spit(cut, bytes);
  EXPECT_NE(message_of(cut).find("truncated"), std::string::npos);
}

TEST_F(SubjectFile, RejectsCorruptContent) {
  std::vector<char> bytes = slurp(path_);
  bytes[bytes.size() / 2] ^= 0x5A;
  const std::string bad = test::scratch_path("flipped.subject");
  spit(bad, bytes);
  EXPECT_NE(message_of(bad).find("CRC"), std::string::npos);
}

TEST_F(SubjectFile, RefusesToWriteAnInconsistentModel) {
  SubjectModel broken = model_;
  broken.pca.pop_back();
  EXPECT_THROW(write_subject(broken, test::scratch_path("broken.subject")), FileError);
}

TEST_F(SubjectFile, RoundTripsExactly) {
  const SubjectModel back = read_subject(path_);
  EXPECT_EQ(back.marker_names, model_.marker_names);
  EXPECT_EQ(back.reference_positions, model_.reference_positions);
  EXPECT_EQ(back.triangles, model_.triangles);
  EXPECT_EQ(back.ring, model_.ring);
  EXPECT_EQ(back.ring_offsets, model_.ring_offsets);
  EXPECT_EQ(back.ring_local_reference, model_.ring_local_reference);
  EXPECT_EQ(back.anchors, model_.anchors);
  ASSERT_EQ(back.pca.size(), model_.pca.size());
  for (size_t i = 0; i < back.pca.size(); ++i) {
    EXPECT_EQ(back.pca[i].mean, model_.pca[i].mean);
    EXPECT_EQ(back.pca[i].basis, model_.pca[i].basis);
    EXPECT_EQ(back.pca[i].variance, model_.pca[i].variance);
    EXPECT_EQ(back.pca[i].slot_calibration, model_.pca[i].slot_calibration);
    EXPECT_EQ(back.pca[i].rigid_variance, model_.pca[i].rigid_variance);
  }
  EXPECT_EQ(back.parameters.alpha1, model_.parameters.alpha1);
}

}  // namespace
}  // namespace skinstream
