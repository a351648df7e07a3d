// Writes the fuzz targets' seeds that no real file is small enough to be: each format written
// by the project's own writers from a cut of a real capture (CMU 85_02) and of the MakeHuman
// body, so every seed is a valid file the mutations start from. Usage: fuzz_make_seeds OUT_DIR
// (writes OUT_DIR/<target>/...).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/offline/subject_builder.h"
#include "protocol/c3d.h"
#include "protocol/capture_file.h"
#include "protocol/mesh_file.h"
#include "protocol/subject_file.h"
#include "protocol/trc.h"
#include "protocol/vicon_capture_encoder.h"
#include "protocol/vicon_packet_writer.h"

namespace fs = std::filesystem;
using namespace skinstream;

namespace {

void write_bytes(const fs::path& path, std::span<const unsigned char> bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// The faces of `mesh` among its first `vertices` vertices.
TriangleMesh cut(const TriangleMesh& mesh, int vertices) {
  TriangleMesh out;
  out.vertices.assign(mesh.vertices.begin(), mesh.vertices.begin() + vertices);
  for (const auto& f : mesh.faces)
    if (f[0] < vertices && f[1] < vertices && f[2] < vertices) out.faces.push_back(f);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  for (const char* target : {"c3d", "trc", "obj", "ply", "subject_file", "vicon_packets", "multicast_datagrams"})
    fs::create_directories(out / target);
  try {
    const Capture full = read_capture(SKINSTREAM_SOURCE_DIR "/replay_data/cmu/85_02.c3d");
    std::vector<int> points;
    for (int p = 0; p < 12; ++p) points.push_back(p);
    const Capture small = full.select(points, 0, 24);

    write_c3d(small, out / "c3d" / "intel_float.c3d");
    write_c3d(small, out / "c3d" / "dec_integer.c3d", {C3dProcessor::Dec, false});
    write_c3d(small, out / "c3d" / "mips_float.c3d", {C3dProcessor::Mips, true});
    write_trc(small, out / "trc" / "small.trc");

    const TriangleMesh body = read_mesh(SKINSTREAM_SOURCE_DIR "/replay_data/makehuman/makehuman_hm08_body_only.obj");
    const TriangleMesh piece = cut(body, 200);
    write_obj(out / "obj" / "piece.obj", piece);
    write_obj(out / "obj" / "piece_normals.obj", piece.vertices, piece.faces, &piece.vertices);
    write_ply(out / "ply" / "piece_binary.ply", piece);
    std::ofstream(out / "ply" / "tetrahedron_ascii.ply")
        << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n4 0 3 2 1\n";

    write_subject(build_subject(full, {}), out / "subject_file" / "cmu_85_02.sks");

    vicon::CaptureFrameEncoder encoder(small, "walker");
    vicon::PacketWriter writer;
    encoder.encode_frame(0, 1, true, writer);
    write_bytes(out / "vicon_packets" / "first_frame.bin", writer.finish());
    std::vector<unsigned char> stream;
    for (int f = 1; f < 4; ++f) {
      encoder.encode_frame(f, static_cast<uint32_t>(f + 1), false, writer);
      const auto packet = writer.finish();
      stream.insert(stream.end(), packet.begin(), packet.end());
    }
    write_bytes(out / "vicon_packets" / "three_frames.bin", stream);

    // The golden frame's two datagrams, each after its 2-byte length: in order, and the last first.
    std::vector<std::vector<unsigned char>> datagrams;
    for (const char* name : {"datagram_0.bin", "datagram_1.bin"}) {
      std::ifstream in(fs::path(SKINSTREAM_SOURCE_DIR "/tests/protocol/fixtures/multicast") / name, std::ios::binary);
      datagrams.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    for (const bool reversed : {false, true}) {
      std::vector<unsigned char> seed;
      for (size_t i = 0; i < datagrams.size(); ++i) {
        const std::vector<unsigned char>& d = datagrams[reversed ? datagrams.size() - 1 - i : i];
        seed.push_back(static_cast<unsigned char>(d.size() & 0xFF));
        seed.push_back(static_cast<unsigned char>(d.size() >> 8));
        seed.insert(seed.end(), d.begin(), d.end());
      }
      write_bytes(out / "multicast_datagrams" / (reversed ? "last_first.bin" : "in_order.bin"), seed);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_make_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
