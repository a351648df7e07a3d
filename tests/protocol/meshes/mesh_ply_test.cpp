#include "protocol/meshes/mesh_ply.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "protocol/files/file_error.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

TEST(MeshPly, RejectsBadIndicesUnwritablePathsAndForeignFiles) {
  EXPECT_THROW(write_ply(test::scratch_path("bad.ply"), {Vec3::Zero()}, std::vector<Face>{{0, 1, 2, -1}}), FileError);
  EXPECT_THROW(write_ply(test::scratch_path("no_dir/x.ply"), {Vec3::Zero()}, std::vector<Face>{}), FileError);
  EXPECT_THROW(read_ply(test::scratch_path("no_such.ply")), FileError);
  const std::string ascii = test::scratch_path("ascii.ply");
  std::ofstream(ascii) << "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  EXPECT_THROW(read_ply(ascii), FileError);
  const std::string truncated = test::scratch_path("truncated.ply");
  std::ofstream(truncated) << "ply\nformat binary_little_endian 1.0\nelement vertex 5\nend_header\nabc";
  EXPECT_THROW(read_ply(truncated), FileError);
}

// Found by fuzzing (tests/fuzz/ply_fuzz.cpp): a face naming a vertex the file does not have was
// read as it was, for the caller to index out of bounds.
TEST(MeshPly, FaceIndexOutOfRangeIsRefused) {
  const std::string fuzzed = test::source_path("tests/protocol/fixtures/fuzz/ply_face_index_out_of_range.ply");
  EXPECT_TRUE(test::throws_file_error([&] { read_ply(fuzzed); }, fuzzed, "uses vertex"));
  const std::string negative = test::scratch_path("negative_index.ply");
  write_ply(negative, {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()}, std::vector<Face>{{0, 1, 2, -1}});
  std::string bytes;
  {
    std::ifstream in(negative, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const int32_t minus_one = -1;
  std::memcpy(&bytes[bytes.size() - 4], &minus_one, 4);  // the triangle's last corner
  std::ofstream(negative, std::ios::binary) << bytes;
  EXPECT_TRUE(test::throws_file_error([&] { read_ply(negative); }, negative, "face 0 uses vertex -1 of 3"));
}

// A header's counts size nothing before the bytes that follow can hold them: a count near 2^64
// was handed to reserve() (std::length_error, not a FileError).
TEST(MeshPly, CountsBeyondTheFileAreRefused) {
  const std::string huge = test::scratch_path("huge_count.ply");
  std::ofstream(huge) << "ply\nformat binary_little_endian 1.0\nelement vertex -1\nelement face 1\nend_header\n";
  EXPECT_TRUE(test::throws_file_error([&] { read_ply(huge); }, huge, "truncated: header says"));
  const std::string no_end = test::scratch_path("no_end_header.ply");
  std::ofstream(no_end) << "ply\nformat binary_little_endian 1.0\nelement vertex 3\n";
  EXPECT_TRUE(test::throws_file_error([&] { read_ply(no_end); }, no_end, "no end_header"));
}

TEST(MeshPly, ReadsFromMemoryAsFromTheFile) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1000.5, 0, 0}, {1000.5, 2000.25, 0}, {0, 2000.25, -3.5}};
  const std::vector<Face> f = {{0, 1, 2, 3}, {0, 2, 3, -1}};
  const std::string path = test::scratch_path("quad_memory.ply");
  write_ply(path, v, f);
  const std::string bytes = test::read_bytes(path);
  const PlyMesh from_file = read_ply(path), from_memory = read_ply_bytes(bytes, "quad.ply");
  EXPECT_EQ(from_memory.vertices, from_file.vertices);
  EXPECT_EQ(from_memory.faces, from_file.faces);
  EXPECT_TRUE(test::throws_file_error([&] { read_ply_bytes(bytes.substr(0, bytes.size() - 1), "quad.ply"); }, "quad.ply",
                                      "truncated"));
}

TEST(MeshPly, QuadsAndTrianglesRoundTrip) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1000.5, 0, 0}, {1000.5, 2000.25, 0}, {0, 2000.25, -3.5}};
  const std::vector<Face> f = {{0, 1, 2, 3}, {0, 2, 3, -1}};
  const std::string path = test::scratch_path("quad.ply");
  write_ply(path, v, f);
  const PlyMesh m = read_ply(path);
  ASSERT_EQ(m.vertices.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_TRUE(m.vertices[i].isApprox(v[i], 1e-6));
  EXPECT_EQ(m.faces, f);
}

}  // namespace
}  // namespace skinstream
