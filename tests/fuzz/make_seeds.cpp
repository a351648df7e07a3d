// Writes the fuzz targets' seeds that no real file is small enough to be: each format written
// by the project's own writers from a cut of a real capture (CMU 85_02) and of the MakeHuman
// body, so every seed is a valid input the mutations start from, and the parts of golden
// messages a target reads alone (a Model's payload, a Frame's parameter block, a command's
// text). Usage: fuzz_make_seeds OUT_DIR (writes OUT_DIR/<target>/...).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "core/offline/subject_builder.h"
#include "core/render/software_rasterizer.h"
#include "protocol/files/c3d.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"
#include "protocol/files/trc.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/natnet/natnet_capture_encoder.h"
#include "protocol/natnet/natnet_writer.h"
#include "protocol/qtm/qtm_capture_encoder.h"
#include "protocol/qtm/qtm_command.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "protocol/subscriber/compressed_vertices.h"
#include "protocol/subscriber/subscriber_stream.h"
#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_packet_writer.h"

namespace fs = std::filesystem;
using namespace skinstream;

namespace {

void write_bytes(const fs::path& path, std::span<const unsigned char> bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void write_text(const fs::path& path, std::string_view text) {
  write_bytes(path, {reinterpret_cast<const unsigned char*>(text.data()), text.size()});
}

std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A golden message's payload (after its 12-byte header) or a QTM packet's text (after its 8).
std::vector<unsigned char> after(const std::vector<unsigned char>& bytes, size_t header) {
  return {bytes.begin() + static_cast<std::ptrdiff_t>(std::min(header, bytes.size())), bytes.end()};
}

const fs::path kFixtures = SKINSTREAM_SOURCE_DIR "/tests/protocol/fixtures";

// The faces of `mesh` among its first `vertices` vertices.
TriangleMesh cut(const TriangleMesh& mesh, int vertices) {
  TriangleMesh out;
  out.vertices.assign(mesh.vertices.begin(), mesh.vertices.begin() + vertices);
  for (const auto& f : mesh.faces)
    if (f[0] < vertices && f[1] < vertices && f[2] < vertices) out.faces.push_back(f);
  return out;
}

// QTM RT: the take's parameters and Data packets as the replay server streams them, the XML and
// command texts alone, and commands the fixtures leave out.
void write_qtm_seeds(const Capture& take, const fs::path& out) {
  qtm::CaptureEncoder encoder({{"85_02", &take}});
  const std::string xml = qtm::write_parameters_xml(encoder.parameters(), qtm::kSpokenMinorVersion);
  write_text(out / "qtm_parameters" / "cmu_85_02.xml", xml);
  std::vector<unsigned char> stream = qtm::encode_text(qtm::PacketType::Xml, xml);
  qtm::DataPacketWriter writer;
  for (uint64_t k = 0; k < 3; ++k) {
    const auto packet = encoder.encode_frame(k, writer);
    stream.insert(stream.end(), packet.begin(), packet.end());
  }
  write_bytes(out / "qtm_packets" / "parameters_and_three_frames.bin", stream);

  const auto text_of = [](const std::string& fixture) {
    std::string text, error;
    if (!qtm::decode_text(read_bytes(kFixtures / "qtm" / fixture), text, error)) throw std::runtime_error(fixture + ": " + error);
    return text;
  };
  write_text(out / "qtm_parameters" / "fixture.xml", text_of("parameters_xml.bin"));
  for (const char* fixture : {"version_command", "get_parameters_command", "stream_frames_command"})
    write_text(out / "qtm_command" / (std::string(fixture) + ".txt"), text_of(std::string(fixture) + ".bin"));
  int n = 0;
  for (const std::string& command : {qtm::stream_frames_command({"3D", "3DNoLabels"}, 5000), std::string("StreamFrames Stop"),
                                     std::string("StreamFrames Frequency:60 UDP:10.0.0.2:6000 3D"),
                                     std::string("StreamFrames FrequencyDivisor:2 3DNoLabels"), std::string("GetState"),
                                     std::string("QTMVersion"), std::string("ByteOrder"), std::string("GetCurrentFrame 3D"),
                                     std::string("Version")})
    write_text(out / "qtm_command" / ("command_" + std::to_string(n++) + ".txt"), command);
}

// NatNet: the take's model definitions and first frame in each layout written.
void write_natnet_seeds(const Capture& take, const fs::path& out) {
  natnet::CaptureEncoder encoder({{"85_02", &take}});
  natnet::ByteVector frame;
  for (const natnet::Version version : {natnet::Version{3, 1}, natnet::Version{4, 0}, natnet::Version{4, 1}}) {
    const std::string layout = std::to_string(version.major) + "_" + std::to_string(version.minor);
    write_bytes(out / "natnet" / ("model_def_" + layout + ".bin"), natnet::encode_model_definitions(encoder.model_definitions(), version));
    encoder.encode(0, version, frame);
    write_bytes(out / "natnet" / ("frame_" + layout + ".bin"), frame);
  }
}

// Subscriber protocol 2: the golden Model's payload and parameter block, the golden compressed
// MeshInfo and Frame as one stream, and a compressed stream
// of the body piece (MeshInfo, then a key frame and three deltas with normals, each coded by the
// daemon's encoder as the piece moves 1.5 mm a frame and bulges).
void write_subscriber_seeds(const TriangleMesh& piece, const fs::path& out) {
  write_bytes(out / "subscriber_model" / "model.bin", after(read_bytes(kFixtures / "subscriber/model.bin"), subscriber::kHeaderBytes));
  const std::vector<unsigned char> parameter_frame = read_bytes(kFixtures / "subscriber/frame_v2_parameters.bin");
  const subscriber::FrameView view =
      subscriber::view_frame(std::span(parameter_frame).subspan(subscriber::kHeaderBytes), subscriber::kVersion2);
  write_bytes(out / "frame_parameters" / "frame_v2_parameters.bin", view.positions);
  std::vector<unsigned char> golden = read_bytes(kFixtures / "subscriber/mesh_info_v2.bin");
  const std::vector<unsigned char> compressed_frame = read_bytes(kFixtures / "subscriber/frame_v2_compressed.bin");
  golden.insert(golden.end(), compressed_frame.begin(), compressed_frame.end());
  write_bytes(out / "compressed_vertices" / "golden.bin", golden);

  const size_t v = piece.vertices.size();
  std::vector<float> reference(3 * v), normals(3 * v);
  const std::vector<Vec3> piece_normals = render::vertex_normals(piece.vertices, piece.faces);
  for (size_t i = 0; i < v; ++i)
    for (int a = 0; a < 3; ++a) {
      reference[3 * i + a] = static_cast<float>(piece.vertices[i][a]);
      normals[3 * i + a] = static_cast<float>(piece_normals[i][a]);
    }
  subscriber::MeshInfo info;
  info.vertex_count = static_cast<uint32_t>(v);
  for (const auto& f : piece.faces)
    info.faces.push_back({static_cast<uint32_t>(f[0]), static_cast<uint32_t>(f[1]), static_cast<uint32_t>(f[2])});
  info.part_count = 1;
  info.dominant_part.assign(v, 0);
  info.source_rate_hz = 120.0f;
  info.subject = "body";
  info.encoding = subscriber::Encoding::Compressed;
  info.compressed_order = subscriber::compressed_vertex_order(reference);
  std::vector<unsigned char> stream = subscriber::encode_mesh_info(info, subscriber::kVersion2);

  subscriber::CompressedVertexEncoder encoder(static_cast<int>(v), info.compressed_order);
  std::vector<unsigned char> blocks(encoder.max_bytes(true));
  std::vector<float> positions(3 * v);
  for (uint32_t f = 0; f < 4; ++f) {
    for (size_t i = 0; i < v; ++i)
      for (int a = 0; a < 3; ++a)
        positions[3 * i + a] = reference[3 * i + a] + (a == 0 ? 1.5f * f : 0.0f) + 0.4f * f * std::sin(0.05f * static_cast<float>(i));
    const subscriber::CompressedBlocks coded = encoder.encode(f, positions, normals, blocks);
    subscriber::FrameInfo frame;
    frame.frame_number = f;
    frame.flags = subscriber::kFrameCompressed | subscriber::kFrameNormals | (coded.key ? subscriber::kFrameKey : 0u);
    frame.vertex_count = static_cast<uint32_t>(v);
    const size_t block_bytes = coded.positions_bytes + coded.normals_bytes;
    std::vector<unsigned char> message(subscriber::frame_message_bytes_with_block(block_bytes, frame.flags, 0));
    subscriber::encode_frame_with_block(frame, std::span(blocks).first(block_bytes), {}, {}, message);
    stream.insert(stream.end(), message.begin(), message.end());
  }
  write_bytes(out / "compressed_vertices" / "body_piece.bin", stream);
  write_bytes(out / "daemon_to_subscriber" / "compressed_body_piece.bin", stream);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  for (const char* target : {"c3d", "trc", "obj", "ply", "subject_file", "vicon_packets", "qtm_packets", "qtm_parameters",
                             "qtm_command", "natnet", "subscriber_model", "frame_parameters", "compressed_vertices",
                             "daemon_to_subscriber", "multicast_datagrams"})
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

    write_qtm_seeds(small, out);
    write_natnet_seeds(small, out);
    write_subscriber_seeds(piece, out);

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
    // The golden offer's one datagram among the frame's: the offer's port is fed the same bytes.
    {
      std::ifstream in(fs::path(SKINSTREAM_SOURCE_DIR "/tests/protocol/fixtures/multicast") / "offer_0.bin",
                       std::ios::binary);
      const std::vector<unsigned char> offer{std::istreambuf_iterator<char>(in),
                                             std::istreambuf_iterator<char>()};
      std::vector<unsigned char> seed;
      for (const std::vector<unsigned char>* d :
           {&std::as_const(datagrams[0]), &offer, &std::as_const(datagrams[1])}) {
        seed.push_back(static_cast<unsigned char>(d->size() & 0xFF));
        seed.push_back(static_cast<unsigned char>(d->size() >> 8));
        seed.insert(seed.end(), d->begin(), d->end());
      }
      write_bytes(out / "multicast_datagrams" / "with_offer.bin", seed);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_make_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
