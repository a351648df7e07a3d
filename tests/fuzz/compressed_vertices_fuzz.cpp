// A compressed subscriber's stream (version 2) as the C++ client library decodes it: messages cut
// by the StreamDecoder; a MeshInfo makes a CompressedVertexDecoder for its vertex count and
// compressed vertex order (refused with std::invalid_argument when the order is not a
// permutation); each compressed Frame that fits it goes through view_frame and
// CompressedVertexDecoder::decode, key frames and deltas in the stream's order. A bad message is
// a one-line DecodeError and the stream goes on (so the frames after it are fuzzed too). What
// decodes is finite, and every normal is of unit length.
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <vector>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/compressed_vertices.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace subscriber = skinstream::subscriber;

namespace {

struct Client {
  std::optional<subscriber::CompressedVertexDecoder> decoder;
  uint32_t vertex_count = 0;
  std::vector<float> positions, normals;

  void on_mesh_info(const subscriber::MeshInfo& info) {
    decoder.reset();
    if (info.encoding != subscriber::Encoding::Compressed) return;
    try {
      decoder.emplace(static_cast<int>(info.vertex_count), info.compressed_order);
    } catch (const std::invalid_argument&) {
      return;  // the client refuses the MeshInfo
    }
    vertex_count = info.vertex_count;
    positions.assign(3 * size_t{vertex_count}, 0.0f);
    normals.assign(positions.size(), 0.0f);
  }

  void on_frame(const subscriber::FrameView& view) {
    if (!decoder || !(view.info.flags & subscriber::kFrameCompressed) || view.info.vertex_count != vertex_count) return;
    const bool with_normals = !view.normals.empty();
    const auto result = decoder->decode(view.positions, view.normals, (view.info.flags & subscriber::kFrameKey) != 0, positions,
                                        with_normals ? std::span<float>(normals) : std::span<float>());
    if (result != subscriber::CompressedVertexDecoder::Result::Decoded) return;
    for (const float p : positions)
      if (!std::isfinite(p)) std::abort();
    for (size_t i = 0; with_normals && i < vertex_count; ++i) {
      const float length = std::sqrt(normals[3 * i] * normals[3 * i] + normals[3 * i + 1] * normals[3 * i + 1] + normals[3 * i + 2] * normals[3 * i + 2]);
      if (length != 0.0f && std::abs(length - 1.0f) > 1e-3f) std::abort();
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  subscriber::StreamDecoder stream(1u << 20);
  stream.feed({data, size});
  Client client;
  for (;;) {
    std::optional<subscriber::RawMessage> message;
    try {
      message = stream.next();
    } catch (const subscriber::DecodeError& e) {
      skinstream::fuzz::expect_one_printable_line(e.what());
      return 0;  // the stream is unusable after a bad header
    }
    if (!message) return 0;
    try {
      if (message->type == subscriber::MessageType::MeshInfo) client.on_mesh_info(subscriber::decode_mesh_info(message->payload, message->version));
      if (message->type == subscriber::MessageType::Frame) client.on_frame(subscriber::view_frame(message->payload, message->version));
    } catch (const subscriber::DecodeError& e) {
      skinstream::fuzz::expect_one_printable_line(e.what());
    }
  }
}
