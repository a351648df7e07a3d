// protocol/mesh_file against an independent reader, OpenMesh (Debian's libopenmesh-dev): what
// skinstream writes (the deformed frames of `skinstream deform`, `skinstream-sub --save-every`)
// must load as the same mesh in other tools, and the shared files must read as OpenMesh reads
// them. skinstream's own readers stay the product's (OpenMesh accepts broken files silently, see
// mesh_file.h); on good files the two must agree vertex for vertex and face for face.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "protocol/meshes/mesh_file.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using OpenMeshTriangles = OpenMesh::TriMesh_ArrayKernelT<>;
using Triangle = std::array<int, 3>;

const char* kBodyObj = "data/meshes/makehuman/makehuman_hm08_body_only.obj";
const char* kBodyPly = "data/meshes/makehuman/makehuman_hm08_body_only_tri.ply";

OpenMeshTriangles read_with_openmesh(const std::string& path, bool normals = false) {
  OpenMeshTriangles mesh;
  OpenMesh::IO::Options options;
  if (normals) {
    mesh.request_vertex_normals();
    options += OpenMesh::IO::Options::VertexNormal;
  }
  EXPECT_TRUE(OpenMesh::IO::read_mesh(mesh, path, options)) << path;
  if (normals) {
    EXPECT_TRUE(options.check(OpenMesh::IO::Options::VertexNormal)) << path << ": no normals read";
  }
  return mesh;
}

// A triangle's corners rotated so the smallest index comes first: the same face whichever corner
// a reader starts from, with its winding kept.
Triangle canonical(Triangle t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

std::vector<Triangle> sorted_faces(const std::vector<Triangle>& faces) {
  std::vector<Triangle> out;
  for (const Triangle& f : faces) out.push_back(canonical(f));
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Triangle> sorted_faces(const OpenMeshTriangles& mesh) {
  std::vector<Triangle> faces;
  for (const auto face : mesh.faces()) {
    Triangle t{};
    int corner = 0;
    for (const auto vertex : face.vertices()) {
      if (corner < 3) t[corner] = vertex.idx();
      ++corner;
    }
    EXPECT_EQ(corner, 3) << "face " << face.idx();
    faces.push_back(t);
  }
  return sorted_faces(faces);
}

// Every vertex at the same place (to float precision relative to the body's size), in the same
// order, and the same triangles with the same winding.
void expect_same_mesh(const TriangleMesh& ours, const OpenMeshTriangles& theirs, const std::string& what) {
  ASSERT_EQ(theirs.n_vertices(), ours.vertices.size()) << what;
  double largest = 0.0, worst = 0.0;
  for (size_t i = 0; i < ours.vertices.size(); ++i) {
    const auto p = theirs.point(OpenMesh::VertexHandle(static_cast<int>(i)));
    for (int a = 0; a < 3; ++a) {
      largest = std::max(largest, std::abs(ours.vertices[i][a]));
      worst = std::max(worst, std::abs(ours.vertices[i][a] - static_cast<double>(p[a])));
    }
  }
  EXPECT_LE(worst, largest * 1e-7) << what << ": a vertex moved (OpenMesh keeps float points)";
  ASSERT_EQ(theirs.n_faces(), ours.faces.size()) << what;
  EXPECT_EQ(sorted_faces(theirs), sorted_faces(ours.faces)) << what;
}

TEST(MeshFileOpenMesh, ReadsTheSharedBodyAsOpenMeshDoes) {
  for (const char* file : {kBodyObj, kBodyPly}) {
    const std::string path = test::shared_path(file);
    const TriangleMesh ours = read_mesh(path);
    ASSERT_GT(ours.faces.size(), 10000u) << file;
    expect_same_mesh(ours, read_with_openmesh(path), file);
  }
}

TEST(MeshFileOpenMesh, OpenMeshReadsThePlyAndObjWeWriteAsTheSameMesh) {
  const TriangleMesh body = read_mesh(test::shared_path(kBodyObj));
  const std::string ply = test::scratch_path("body_for_openmesh.ply");
  const std::string obj = test::scratch_path("body_for_openmesh.obj");
  write_ply(ply, body);
  write_obj(obj, body);
  expect_same_mesh(body, read_with_openmesh(ply), "our PLY");
  expect_same_mesh(body, read_with_openmesh(obj), "our OBJ");
}

TEST(MeshFileOpenMesh, OpenMeshReadsTheNormalsOfOurObj) {
  const TriangleMesh body = read_mesh(test::shared_path(kBodyObj));
  std::vector<Vec3> normals(body.vertices.size(), Vec3::Zero());
  for (const Triangle& f : body.faces) {
    const Vec3 n = (body.vertices[f[1]] - body.vertices[f[0]]).cross(body.vertices[f[2]] - body.vertices[f[0]]);
    for (int v : f) normals[v] += n;
  }
  for (Vec3& n : normals) n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 1);
  const std::string obj = test::scratch_path("body_with_normals_for_openmesh.obj");
  write_obj(obj, body.vertices, body.faces, &normals);
  const OpenMeshTriangles theirs = read_with_openmesh(obj, true);
  expect_same_mesh(body, theirs, "our OBJ with normals");
  double worst = 0.0;
  for (size_t i = 0; i < normals.size(); ++i) {
    const auto n = theirs.normal(OpenMesh::VertexHandle(static_cast<int>(i)));
    for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(normals[i][a] - static_cast<double>(n[a])));
  }
  EXPECT_LE(worst, 1e-6);
}

}  // namespace
}  // namespace skinstream
