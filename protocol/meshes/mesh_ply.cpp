#include "protocol/meshes/mesh_ply.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "protocol/files/file_error.h"

namespace skinstream {

namespace {

void put_le(std::string& out, const void* p, size_t n) {
  // Hosts are little-endian (x86-64, arm64); PLY says so in the header.
  out.append(static_cast<const char*>(p), n);
}

}  // namespace

void write_ply(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<Face>& faces) {
  for (size_t f = 0; f < faces.size(); ++f) {
    const int k = faces[f][3] < 0 ? 3 : 4;
    for (int i = 0; i < k; ++i)
      if (faces[f][static_cast<size_t>(i)] < 0 ||
          faces[f][static_cast<size_t>(i)] >= static_cast<int>(vertices.size()))
        throw FileError(path, "face " + std::to_string(f) + " uses vertex " +
                                  std::to_string(faces[f][static_cast<size_t>(i)]) + " of " +
                                  std::to_string(vertices.size()));
  }
  std::string data;
  data +=
      "ply\nformat binary_little_endian 1.0\ncomment skinstream synthetic truth mesh, millimetres, Z up\n";
  data += "element vertex " + std::to_string(vertices.size()) + "\n";
  data += "property float x\nproperty float y\nproperty float z\n";
  data += "element face " + std::to_string(faces.size()) + "\n";
  data += "property list uchar int vertex_indices\nend_header\n";
  data.reserve(data.size() + vertices.size() * 12 + faces.size() * 17);
  for (const Vec3& v : vertices) {
    const float xyz[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
    put_le(data, xyz, sizeof xyz);
  }
  for (const Face& f : faces) {
    const uint8_t k = f[3] < 0 ? 3 : 4;
    put_le(data, &k, 1);
    for (int i = 0; i < k; ++i) {
      const int32_t idx = f[static_cast<size_t>(i)];
      put_le(data, &idx, 4);
    }
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot create");
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
  if (!out) throw FileError(path, "write failed");
}

namespace {

PlyMesh parse_ply(const std::string& path, std::istream& in) {
  std::string line;
  size_t nv = 0, nf = 0;
  if (!std::getline(in, line) || line != "ply") throw FileError(path, "not a PLY file");
  bool binary_le = false;
  while (std::getline(in, line)) {
    if (line == "end_header") break;
    std::istringstream s(line);
    std::string a, b;
    s >> a >> b;
    if (a == "format") binary_le = b == "binary_little_endian";
    if (a == "element" && b == "vertex") s >> nv;
    if (a == "element" && b == "face") s >> nf;
  }
  if (!in) throw FileError(path, "truncated: the header has no end_header");
  if (!binary_le) throw FileError(path, "only binary little-endian PLY is read");
  // The counts are judged against the bytes that follow before anything is sized by them.
  const std::streamoff header_end = in.tellg();
  in.seekg(0, std::ios::end);
  const auto data_bytes = static_cast<uint64_t>(in.tellg() - header_end);
  in.seekg(header_end);
  constexpr uint64_t kVertexBytes = 12, kMinFaceBytes = 1 + 3 * 4;
  if (nv > data_bytes / kVertexBytes || nf > (data_bytes - nv * kVertexBytes) / kMinFaceBytes)
    throw FileError(path, "truncated: header says " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                              " faces, the file holds " + std::to_string(data_bytes) + " bytes of data");
  PlyMesh mesh;
  mesh.vertices.reserve(nv);
  for (size_t i = 0; i < nv; ++i) {
    float xyz[3];
    if (!in.read(reinterpret_cast<char*>(xyz), sizeof xyz)) throw FileError(path, "truncated vertex data");
    mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  for (size_t i = 0; i < nf; ++i) {
    uint8_t k = 0;
    if (!in.read(reinterpret_cast<char*>(&k), 1) || (k != 3 && k != 4))
      throw FileError(path, "bad face " + std::to_string(i));
    int32_t idx[4] = {0, 0, 0, -1};
    if (!in.read(reinterpret_cast<char*>(idx), 4 * k)) throw FileError(path, "truncated face data");
    for (int c = 0; c < k; ++c)
      if (idx[c] < 0 || static_cast<size_t>(idx[c]) >= nv)
        throw FileError(path, "face " + std::to_string(i) + " uses vertex " + std::to_string(idx[c]) + " of " + std::to_string(nv));
    mesh.faces.push_back({idx[0], idx[1], idx[2], k == 4 ? idx[3] : -1});
  }
  return mesh;
}

}  // namespace

PlyMesh read_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "cannot open");
  return parse_ply(path, in);
}

PlyMesh read_ply_bytes(std::string_view bytes, const std::string& name) {
  std::istringstream in{std::string(bytes)};
  return parse_ply(name, in);
}

}  // namespace skinstream
