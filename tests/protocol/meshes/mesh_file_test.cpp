#include "protocol/meshes/mesh_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "protocol/files/file_error.h"
#include "protocol/meshes/mesh_ply.h"
#include "protocol/offline/makehuman.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::read_bytes;
using test::write_bytes;

using Triangles = std::vector<std::array<int, 3>>;

const char* kBody = "data/meshes/makehuman/makehuman_hm08_body_only.obj";

template <typename T>
void put(std::string& out, T value, bool big_endian = false) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

const std::string kAsciiTetra =
    "ply\nformat ascii 1.0\ncomment a tetrahedron with one quad-free face list\n"
    "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

TEST(MeshFile, RejectsMissingFilesUnknownExtensionsAndEmptyFiles) {
  EXPECT_TRUE(test::throws_file_error([] { read_mesh(test::scratch_path("no_such.obj")); },
                                      test::scratch_path("no_such.obj"), "cannot open"));
  const std::string stl = test::scratch_path("mesh.stl");
  write_bytes(stl, "solid x\nendsolid x\n");
  EXPECT_TRUE(test::throws_file_error([&] { read_mesh(stl); }, stl, "unknown mesh extension '.stl'"));
  const std::string none = test::scratch_path("mesh_without_extension");
  write_bytes(none, kAsciiTetra);
  EXPECT_TRUE(test::throws_file_error([&] { read_mesh(none); }, none, "unknown mesh extension"));
  for (const char* name : {"empty.obj", "empty.ply"}) {
    const std::string path = test::scratch_path(name);
    write_bytes(path, "");
    EXPECT_TRUE(test::throws_file_error([&] { read_mesh(path); }, path, "empty file"));
  }
}

TEST(MeshFile, RejectsBrokenObjFiles) {
  const std::string path = test::scratch_path("broken.obj");
  const std::pair<std::string, std::string> cases[] = {
      {"v 0 0 0\nv 1 abc 0\nv 0 1 0\nf 1 2 3\n", "line 2: bad number 'abc'"},
      {"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "line 2: a vertex needs 3 coordinates"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "face index 3 out of range (3 vertices)"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "line 4: face index -4 out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "line 4: bad face index '0'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4: a face needs at least 3 vertices"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad face index 'x'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"},
      {"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", "vertex 1 has a non-finite coordinate"},
      {"v 0 0 0\nv 1 1e999 0\nv 0 1 0\nf 1 2 3\n", "line 2: bad number '1e999'"},
      {"v 0 0 0\n\x01\x02garbage\nf 1 1 1\n", "line 2: not an OBJ statement"},
  };
  for (const auto& [text, fragment] : cases) {
    write_bytes(path, text);
    EXPECT_TRUE(test::throws_file_error([&] { read_mesh(path); }, path, fragment)) << text;
  }
}

TEST(MeshFile, ReadsTheMakeHumanBodyInFileOrder) {
  const std::string path = test::shared_path(kBody);
  const TriangleMesh mesh = read_mesh(path);
  ASSERT_EQ(mesh.vertices.size(), 13380u);
  ASSERT_EQ(mesh.faces.size(), 26756u);  // 13,378 quads, each fanned into two triangles
  EXPECT_TRUE(mesh.vertices[0].isApprox(Vec3(-0.3492, 7.3299, 1.4076)));
  // First line "f 4849/1 1/2 2/3 4848/4": the quad (4848, 0, 1, 4847) fanned from its first corner.
  EXPECT_EQ(mesh.faces[0], (std::array<int, 3>{4848, 0, 1}));
  EXPECT_EQ(mesh.faces[1], (std::array<int, 3>{4848, 1, 4847}));
  // The body loader's own OBJ reader agrees vertex by vertex and face by face.
  const ObjMesh reference = read_obj(path);
  ASSERT_EQ(reference.vertices.size(), mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    ASSERT_EQ(reference.vertices[i], mesh.vertices[i]) << i;
  }
  size_t t = 0;
  for (const Face& f : reference.faces) {
    ASSERT_EQ(mesh.faces[t++], (std::array<int, 3>{f[0], f[1], f[2]}));
    if (f[3] >= 0) {
      ASSERT_EQ(mesh.faces[t++], (std::array<int, 3>{f[0], f[2], f[3]}));
    }
  }
  EXPECT_EQ(t, mesh.faces.size());
}

TEST(MeshFile, ReadsTheSharedAsciiPlyOfTheSameBody) {
  const TriangleMesh obj = read_mesh(test::shared_path(kBody));
  const TriangleMesh ply = read_mesh(test::shared_path("data/meshes/makehuman/makehuman_hm08_body_only_tri.ply"));
  ASSERT_EQ(ply.vertices.size(), obj.vertices.size());
  ASSERT_EQ(ply.faces.size(), obj.faces.size());
  for (size_t i = 0; i < obj.vertices.size(); ++i) ASSERT_TRUE(ply.vertices[i].isApprox(obj.vertices[i], 1e-6)) << i;
  EXPECT_EQ(ply.faces, obj.faces);
}

TEST(MeshFile, ReadsFromMemoryAsFromTheFile) {
  for (const std::string& file : {std::string(kBody), std::string("data/meshes/makehuman/makehuman_hm08_body_only_tri.ply")}) {
    SCOPED_TRACE(file);
    const TriangleMesh from_file = read_mesh(test::shared_path(file));
    const TriangleMesh from_memory = read_mesh_bytes(read_bytes(test::shared_path(file)), file);
    EXPECT_EQ(from_memory.vertices, from_file.vertices);
    EXPECT_EQ(from_memory.faces, from_file.faces);
  }
  // The name's extension says the format, and the name stands for the path in errors.
  EXPECT_EQ(read_mesh_bytes(kAsciiTetra, "tetra.PLY").faces.size(), 4u);
  EXPECT_TRUE(test::throws_file_error([] { read_mesh_bytes(kAsciiTetra, "tetra.obj"); }, "tetra.obj", "line 1"));
  EXPECT_TRUE(test::throws_file_error([] { read_mesh_bytes(kAsciiTetra, "tetra.stl"); }, "tetra.stl", "unknown mesh extension"));
  EXPECT_TRUE(test::throws_file_error([] { read_mesh_bytes("", "empty.ply"); }, "empty.ply", "empty file"));
}

TEST(MeshFile, PlyFromTheGeneratorRoundTripsWithQuadsFanned) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1000.5, 0, 0}, {1000.5, 2000.25, 0}, {0, 2000.25, -3.5}};
  const std::vector<Face> f = {{0, 1, 2, 3}, {3, 2, 1, -1}};
  const std::string path = test::scratch_path("generator.ply");
  write_ply(path, v, f);
  const TriangleMesh m = read_mesh(path);
  ASSERT_EQ(m.vertices.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(m.vertices[i], v[i]);  // all exact in float
  EXPECT_EQ(m.faces, (Triangles{{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));
}

TEST(MeshFile, ObjAndTrianglePlyRoundTrip) {
  const TriangleMesh body = read_mesh(test::shared_path(kBody));
  TriangleMesh mm = body;
  for (Vec3& p : mm.vertices) p = makehuman_to_skinstream(p) + Vec3(0.1234567891234, -7.0, 1e-9);
  const std::string obj = test::scratch_path("round_trip.obj");
  write_obj(obj, mm);
  const TriangleMesh back = read_mesh(obj);
  EXPECT_EQ(back.vertices, mm.vertices);  // shortest round-trip text: bit-exact
  EXPECT_EQ(back.faces, mm.faces);

  const std::string ply = test::scratch_path("round_trip.ply");
  write_ply(ply, mm);
  const TriangleMesh back_ply = read_mesh(ply);
  ASSERT_EQ(back_ply.vertices.size(), mm.vertices.size());
  for (size_t i = 0; i < mm.vertices.size(); ++i)
    ASSERT_EQ(back_ply.vertices[i], mm.vertices[i].cast<float>().cast<double>()) << i;
  EXPECT_EQ(back_ply.faces, mm.faces);
}

TEST(MeshFile, ObjWithNormalsReadsBackTheSameMesh) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<Vec3> n = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  const std::string path = test::scratch_path("normals.obj");
  write_obj(path, v, {{0, 1, 2}}, &n);
  EXPECT_NE(read_bytes(path).find("vn 0 0 1\n"), std::string::npos);
  EXPECT_NE(read_bytes(path).find("f 1//1 2//2 3//3\n"), std::string::npos);
  const TriangleMesh m = read_mesh(path);
  EXPECT_EQ(m.vertices, v);
  EXPECT_EQ(m.faces, (Triangles{{0, 1, 2}}));
  const std::vector<Vec3> too_few = {{0, 0, 1}};
  EXPECT_TRUE(test::throws_file_error([&] { write_obj(path, v, {{0, 1, 2}}, &too_few); }, path, "1 normals for 3"));
  EXPECT_TRUE(test::throws_file_error([&] { write_obj(path, v, {{0, 1, 3}}); }, path, "uses vertex 3 of 3"));
  EXPECT_THROW(write_obj(test::scratch_path("no_dir/x.obj"), v, {{0, 1, 2}}), FileError);
}

TEST(MeshFile, ReadsAsciiPlyWithExtraPropertiesAndElements) {
  const std::string path = test::scratch_path("tetra.ply");
  write_bytes(path, kAsciiTetra);
  const TriangleMesh m = read_mesh(path);
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.faces, (Triangles{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}));

  // Colours, normals, an edge element, CRLF line ends and a pentagon are all fine.
  const std::string rich = test::scratch_path("rich.PLY");
  write_bytes(rich,
              "ply\r\nformat ascii 1.0\r\nelement vertex 5\r\nproperty double nx\r\nproperty float x\r\n"
              "property float y\r\nproperty float z\r\nproperty uchar red\r\nelement face 1\r\n"
              "property uchar flags\r\nproperty list uchar uint vertex_index\r\nelement edge 1\r\n"
              "property int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
              "9 0 0 0 255\r\n9 1 0 0 255\r\n9 1 1 0 255\r\n9 0.5 1.5 0 255\r\n9 0 1 -2.5e1 255\r\n"
              "7 5 0 1 2 3 4\r\n0 1\r\n");
  const TriangleMesh r = read_mesh(rich);
  ASSERT_EQ(r.vertices.size(), 5u);
  EXPECT_EQ(r.vertices[4], Vec3(0, 1, -25));
  EXPECT_EQ(r.faces, (Triangles{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
}

TEST(MeshFile, ReadsBigEndianBinaryPly) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
      "property double z\nelement face 1\nproperty list uchar ushort vertex_indices\nend_header\n";
  for (double c : {1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, -9.25}) put(bytes, c, true);
  put<uint8_t>(bytes, 3);
  for (uint16_t i : {2, 1, 0}) put(bytes, i, true);
  const std::string path = test::scratch_path("big_endian.ply");
  write_bytes(path, bytes);
  const TriangleMesh m = read_mesh(path);
  ASSERT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(m.vertices[0], Vec3(1.5, 2, 3));
  EXPECT_EQ(m.vertices[2], Vec3(7, 8, -9.25));
  EXPECT_EQ(m.faces, (Triangles{{2, 1, 0}}));
}

TEST(MeshFile, RejectsBrokenPlyFiles) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string vertices;
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(vertices, c);
  auto face = [](uint8_t n, std::initializer_list<int32_t> idx) {
    std::string s;
    put(s, n);
    for (int32_t i : idx) put(s, i);
    return s;
  };
  std::string nan_vertices = vertices;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_vertices.data() + 16, &nan, 4);
  const std::pair<std::string, std::string> cases[] = {
      {header + vertices + face(3, {0, 1, 2}) + "x", "corrupt: 1 bytes after the last element"},
      {header + vertices + face(2, {0, 1}), "face 0 has 2 vertices"},
      {header + vertices + face(3, {0, 1, 3}), "face index 3 out of range (3 vertices)"},
      {header + vertices + face(3, {0, 1, -1}), "face index -1 out of range"},
      {header + vertices + face(3, {0, 1}), "truncated: file ends in face 0"},
      {header + vertices.substr(0, 20), "truncated: header says 3 vertex elements"},
      {header.substr(0, 40), "truncated PLY header"},
      {header + nan_vertices + face(3, {0, 1, 2}), "vertex 1 has a non-finite coordinate"},
      {"PLY\n" + header.substr(4), "not a PLY file"},
      {"ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n",
       "vertex element lacks x, y or z"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "end_header\n1 2 3\n",
       "no faces"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "truncated: file ends before face 1"},
      {kAsciiTetra.substr(0, kAsciiTetra.size() - 3), "too few values in face 3"},
      {kAsciiTetra + "3 0 1 2\n", "corrupt: data after the last element"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
       "vertex 1 has a non-finite coordinate"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n",
       "extra values in vertex 1"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n",
       "bad integer '1.5' in face 0"},
  };
  const std::string path = test::scratch_path("broken.ply");
  for (const auto& [bytes, fragment] : cases) {
    write_bytes(path, bytes);
    EXPECT_TRUE(test::throws_file_error([&] { read_mesh(path); }, path, fragment)) << fragment;
  }
}

// Every damaged copy of a valid file is either read as a valid mesh or refused with a
// FileError naming the file; never a crash, a hang or a foreign exception.
void expect_reads_or_refuses(const std::string& path) {
  try {
    const TriangleMesh m = read_mesh(path);
    ASSERT_FALSE(m.faces.empty());
    for (const auto& f : m.faces)
      for (int v : f) ASSERT_TRUE(v >= 0 && v < static_cast<int>(m.vertices.size()));
    for (const Vec3& p : m.vertices) ASSERT_TRUE(p.allFinite());
  } catch (const FileError& e) {
    ASSERT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    ASSERT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

TEST(MeshFile, DamagedFilesAreReadOrRefusedNeverCrash) {
  // A small part of the real body in each format: its first 300 vertices and their faces.
  const TriangleMesh body = read_mesh(test::shared_path(kBody));
  TriangleMesh small;
  small.vertices.assign(body.vertices.begin(), body.vertices.begin() + 300);
  for (const auto& f : body.faces)
    if (f[0] < 300 && f[1] < 300 && f[2] < 300) small.faces.push_back(f);
  ASSERT_GT(small.faces.size(), 100u);
  const std::string originals[] = {test::scratch_path("small.ply"), test::scratch_path("small.obj")};
  write_ply(originals[0], small);
  write_obj(originals[1], small);
  const std::string ascii_ply = test::scratch_path("small_ascii.ply");
  write_bytes(ascii_ply, kAsciiTetra);

  std::mt19937 rng(20061);
  int refused = 0, total = 0;
  for (const std::string& original : {originals[0], originals[1], ascii_ply}) {
    const std::string good = read_bytes(original);
    const std::string damaged = test::scratch_path("damaged" + original.substr(original.size() - 4));
    for (int round = 0; round < 150; ++round, ++total) {
      std::string bytes = good;
      switch (round % 3) {
        case 0:  // truncation
          bytes.resize(std::uniform_int_distribution<size_t>(0, good.size() - 1)(rng));
          break;
        case 1:  // a few random bytes overwritten
          for (int k = 0; k < 1 + round % 5; ++k)
            bytes[std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(rng)] =
                static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
          break;
        default:  // a run of garbage inserted
          bytes.insert(std::uniform_int_distribution<size_t>(0, bytes.size())(rng),
                       std::string(1 + round % 17, static_cast<char>(rng() & 0xff)));
      }
      write_bytes(damaged, bytes);
      bool threw = false;
      try {
        read_mesh(damaged);
      } catch (const FileError&) {
        threw = true;
      }
      refused += threw;
      expect_reads_or_refuses(damaged);
      // A binary PLY cut anywhere short of its end is always refused.
      if (round % 3 == 0 && original == originals[0]) {
        EXPECT_TRUE(threw) << "cut at " << bytes.size();
      }
    }
  }
  EXPECT_GT(refused, total / 2);
}

}  // namespace
}  // namespace skinstream
