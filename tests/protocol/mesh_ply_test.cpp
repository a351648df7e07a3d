#include "protocol/mesh_ply.h"

#include <gtest/gtest.h>

#include <fstream>

#include "protocol/file_error.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

TEST(MeshPly, RejectsBadIndicesUnwritablePathsAndForeignFiles) {
  EXPECT_THROW(write_ply(test::scratch_path("bad.ply"), {Vec3::Zero()}, {{0, 1, 2, -1}}), FileError);
  EXPECT_THROW(write_ply(test::scratch_path("no_dir/x.ply"), {Vec3::Zero()}, {}), FileError);
  EXPECT_THROW(read_ply(test::scratch_path("no_such.ply")), FileError);
  const std::string ascii = test::scratch_path("ascii.ply");
  std::ofstream(ascii) << "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  EXPECT_THROW(read_ply(ascii), FileError);
  const std::string truncated = test::scratch_path("truncated.ply");
  std::ofstream(truncated) << "ply\nformat binary_little_endian 1.0\nelement vertex 5\nend_header\nabc";
  EXPECT_THROW(read_ply(truncated), FileError);
}

TEST(MeshPly, QuadsAndTrianglesRoundTrip) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1000.5, 0, 0}, {1000.5, 2000.25, 0}, {0, 2000.25, -3.5}};
  const std::vector<synth::Face> f = {{0, 1, 2, 3}, {0, 2, 3, -1}};
  const std::string path = test::scratch_path("quad.ply");
  write_ply(path, v, f);
  const PlyMesh m = read_ply(path);
  ASSERT_EQ(m.vertices.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_TRUE(m.vertices[i].isApprox(v[i], 1e-6));
  EXPECT_EQ(m.faces, f);
}

}  // namespace
}  // namespace skinstream
