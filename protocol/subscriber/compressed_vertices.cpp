#include "protocol/subscriber/compressed_vertices.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"
#include "protocol/span_writer.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::subscriber {
namespace {

constexpr size_t kPositionHeaderBytes = 32;  // key frame number, origin, step, coded bytes
constexpr size_t kPositionVertexBytes = 8;   // u16 x y z and a zero (the codec wants multiples of 4)
constexpr size_t kNormalVertexBytes = 4;     // i8 octahedral x y, 127, 0

// The identity when `order` is empty; otherwise checked to be a permutation of 0..count-1.
std::vector<uint32_t> checked_order(std::vector<uint32_t> order, int count) {
  if (order.empty()) {
    order.resize(static_cast<size_t>(count));
    for (int v = 0; v < count; ++v) order[v] = static_cast<uint32_t>(v);
    return order;
  }
  std::vector<char> seen(static_cast<size_t>(count), 0);
  bool permutation = order.size() == static_cast<size_t>(count);
  for (size_t i = 0; permutation && i < order.size(); ++i) {
    permutation = order[i] < static_cast<uint32_t>(count) && !seen[order[i]];
    if (permutation) seen[order[i]] = 1;
  }
  if (!permutation) throw std::invalid_argument("the compressed vertex order is not a permutation of the " + std::to_string(count) + " vertices");
  return order;
}

}  // namespace

std::vector<uint32_t> compressed_vertex_order(std::span<const float> reference_positions) {
  const size_t v = reference_positions.size() / 3;
  std::vector<unsigned int> remap(v);  // remap[vertex] = its position in the order
  if (v > 0) meshopt_spatialSortRemap(remap.data(), reference_positions.data(), v, 3 * sizeof(float));
  std::vector<uint32_t> order(v);
  for (size_t i = 0; i < v; ++i) order[remap[i]] = static_cast<uint32_t>(i);
  return order;
}

CompressedVertexEncoder::CompressedVertexEncoder(int vertex_count, std::vector<uint32_t> order, int key_interval, float margin_mm)
    : vertex_count_(vertex_count), key_interval_(std::max(key_interval, 1)), margin_mm_(std::max(margin_mm, 0.0f)) {
  if (vertex_count < 0) throw std::invalid_argument("CompressedVertexEncoder: negative vertex count");
  order_ = checked_order(std::move(order), vertex_count);
  key_q_.assign(4 * static_cast<size_t>(vertex_count), 0);
  vertices_.assign(4 * static_cast<size_t>(vertex_count), 0);
  octahedral_in_.assign(4 * static_cast<size_t>(vertex_count), 0.0f);
  octahedral_.assign(4 * static_cast<size_t>(vertex_count), 0);
}

size_t CompressedVertexEncoder::max_bytes(bool normals) const {
  const size_t v = static_cast<size_t>(vertex_count_);
  const size_t coded = meshopt_encodeVertexBufferBound(v, kPositionVertexBytes);
  size_t bytes = kPositionHeaderBytes + coded + 3;
  if (normals) bytes += 4 + meshopt_encodeVertexBufferBound(v, kNormalVertexBytes) + 3;
  return bytes;
}

CompressedBlocks CompressedVertexEncoder::encode(uint32_t frame_number, std::span<const float> positions, std::span<const float> normals,
                                                 std::span<unsigned char> out) {
  const size_t v3 = 3 * static_cast<size_t>(vertex_count_);
  if (positions.size() != v3 || (!normals.empty() && normals.size() != v3) || out.size() < max_bytes(!normals.empty()))
    throw std::invalid_argument("CompressedVertexEncoder::encode: buffer sizes do not match the vertex count");
  CompressedBlocks blocks;
  blocks.positions_bytes = encode_positions(frame_number, positions, blocks.key, out.data());
  if (!normals.empty()) blocks.normals_bytes = encode_normals(normals, out.data() + blocks.positions_bytes);
  return blocks;
}

size_t CompressedVertexEncoder::encode_positions(uint32_t frame_number, std::span<const float> positions, bool& key,
                                                 unsigned char* out) {
  const size_t v = static_cast<size_t>(vertex_count_);
  key = since_key_ < 0 || since_key_ + 1 >= key_interval_ || key_requested_.exchange(false, std::memory_order_relaxed);
  if (!key) {
    // On the key's grid, as differences from the key modulo 2^16 (exact, both being on the
    // grid); a coordinate off the grid (or not finite) makes this frame a key instead. One pass
    // without an early exit, so that it runs in vector lanes: it was most of the encoding.
    const float inverse[3] = {1.0f / step_[0], 1.0f / step_[1], 1.0f / step_[2]};
    bool off_grid = false;
    for (size_t i = 0; i < v; ++i) {
      const float* x = &positions[3 * size_t{order_[i]}];
      for (int a = 0; a < 3; ++a) {
        const float q = std::nearbyint((x[a] - origin_[a]) * inverse[a]);
        off_grid |= !(q >= 0.0f && q <= 65535.0f);
        vertices_[4 * i + a] = static_cast<uint16_t>(static_cast<uint16_t>(static_cast<int32_t>(q)) - key_q_[4 * i + a]);
      }
    }
    key = off_grid;
  }
  if (key) {
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<float>::max(), hi[a] = std::numeric_limits<float>::lowest();
    for (size_t i = 0; i < v; ++i)
      for (int a = 0; a < 3; ++a) {
        const float x = positions[3 * i + a];
        if (!std::isfinite(x)) continue;
        lo[a] = std::min(lo[a], x);
        hi[a] = std::max(hi[a], x);
      }
    for (int a = 0; a < 3; ++a) {
      if (lo[a] > hi[a]) lo[a] = hi[a] = 0.0f;  // no finite value on this axis
      origin_[a] = lo[a] - margin_mm_;
      step_[a] = std::max((hi[a] - lo[a] + 2.0f * margin_mm_) / 65535.0f, 1e-6f);
    }
    const float inverse[3] = {1.0f / step_[0], 1.0f / step_[1], 1.0f / step_[2]};
    for (size_t i = 0; i < v; ++i) {
      const float* x = &positions[3 * size_t{order_[i]}];
      for (int a = 0; a < 3; ++a) {
        const float q = std::isfinite(x[a]) ? std::nearbyint((x[a] - origin_[a]) * inverse[a]) : 0.0f;
        key_q_[4 * i + a] = vertices_[4 * i + a] = static_cast<uint16_t>(std::clamp(q, 0.0f, 65535.0f));
      }
    }
    key_frame_number_ = frame_number;
    since_key_ = 0;
  } else {
    ++since_key_;
  }
  const size_t bound = meshopt_encodeVertexBufferBound(v, kPositionVertexBytes);
  SpanWriter w(std::span(out, kPositionHeaderBytes + bound + 3));
  w.put<uint32_t>(key_frame_number_);
  w.put_array<float>(origin_);
  w.put_array<float>(step_);
  unsigned char* count_at = w.reserve(4);
  const size_t coded = meshopt_encodeVertexBuffer(out + kPositionHeaderBytes, bound, vertices_.data(), v,
                                                  kPositionVertexBytes);
  if (coded == 0 && v > 0) throw std::runtime_error("meshopt_encodeVertexBuffer failed");
  SpanWriter(std::span(count_at, 4)).put<uint32_t>(static_cast<uint32_t>(coded));
  std::memset(out + kPositionHeaderBytes + coded, 0, padding_to_4(coded));
  return kPositionHeaderBytes + coded + padding_to_4(coded);
}

size_t CompressedVertexEncoder::encode_normals(std::span<const float> normals, unsigned char* out) {
  const size_t v = static_cast<size_t>(vertex_count_);
  for (size_t i = 0; i < v; ++i) {
    for (int a = 0; a < 3; ++a) {
      const float n = normals[3 * size_t{order_[i]} + a];
      octahedral_in_[4 * i + a] = std::isfinite(n) ? n : 0.0f;
    }
    octahedral_in_[4 * i + 3] = 0.0f;
  }
  meshopt_encodeFilterOct(octahedral_.data(), v, kNormalVertexBytes, 8, octahedral_in_.data());
  const size_t coded = meshopt_encodeVertexBuffer(out + 4, meshopt_encodeVertexBufferBound(v, kNormalVertexBytes), octahedral_.data(), v,
                                                  kNormalVertexBytes);
  if (coded == 0 && v > 0) throw std::runtime_error("meshopt_encodeVertexBuffer failed");
  SpanWriter(std::span(out, 4)).put<uint32_t>(static_cast<uint32_t>(coded));
  std::memset(out + 4 + coded, 0, padding_to_4(coded));
  return 4 + coded + padding_to_4(coded);
}

CompressedVertexDecoder::CompressedVertexDecoder(int vertex_count, std::vector<uint32_t> order) : vertex_count_(vertex_count) {
  if (vertex_count < 0) throw std::invalid_argument("CompressedVertexDecoder: negative vertex count");
  order_ = checked_order(std::move(order), vertex_count);
  key_q_.assign(4 * static_cast<size_t>(vertex_count), 0);
  vertices_.assign(4 * static_cast<size_t>(vertex_count), 0);
  octahedral_.assign(4 * static_cast<size_t>(vertex_count), 0);
}

CompressedVertexDecoder::Result CompressedVertexDecoder::decode(std::span<const unsigned char> positions_block,
                                                                std::span<const unsigned char> normals_block, bool key,
                                                                std::span<float> positions, std::span<float> normals) {
  const size_t v = static_cast<size_t>(vertex_count_);
  if (positions.size() < 3 * v || (!normals.empty() && normals.size() < 3 * v))
    throw std::invalid_argument("CompressedVertexDecoder::decode: output smaller than the mesh");
  if (positions_block.size() < kPositionHeaderBytes) throw DecodeError("compressed positions: block truncated");
  ByteReader r(positions_block);  // its size checked: the header's reads cannot fail
  const uint32_t key_frame_number = r.get<uint32_t>("key frame number");
  float origin[3], step[3];
  r.get_array(origin, 3, "grid origin");
  r.get_array(step, 3, "grid step");
  const uint32_t coded = r.get<uint32_t>("coded bytes");
  if (kPositionHeaderBytes + coded + padding_to_4(coded) != positions_block.size())
    throw DecodeError("compressed positions: " + std::to_string(coded) + " coded bytes in a block of " + std::to_string(positions_block.size()));
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(origin[a]) || !std::isfinite(step[a]) || step[a] <= 0.0f)
      throw DecodeError("compressed positions: the grid's origin or step is not a finite positive number");
    // Every position is origin + q * step with q < 65536: finite at both ends, finite between.
    const float span = 65535.0f * step[a];
    if (!std::isfinite(span) || !std::isfinite(origin[a] + span))
      throw DecodeError("compressed positions: the grid reaches beyond the range of a float");
  }
  if (!key && (!has_key_ || key_frame_number != key_frame_number_)) return Result::NeedsKey;
  if (meshopt_decodeVertexBuffer(vertices_.data(), v, kPositionVertexBytes, r.here(), coded) != 0)
    throw DecodeError("compressed positions: the vertex codec refused the data");
  if (key) {
    key_q_ = vertices_;  // same size: copies, never allocates
    key_frame_number_ = key_frame_number;
    std::copy(origin, origin + 3, origin_);
    std::copy(step, step + 3, step_);
    has_key_ = true;
  }
  for (size_t i = 0; i < v; ++i)
    for (int a = 0; a < 3; ++a) {
      const uint16_t q = key ? vertices_[4 * i + a] : static_cast<uint16_t>(key_q_[4 * i + a] + vertices_[4 * i + a]);
      positions[3 * size_t{order_[i]} + a] = origin_[a] + q * step_[a];
    }
  if (!normals.empty() && !normals_block.empty()) {
    if (normals_block.size() < 4) throw DecodeError("compressed normals: block truncated");
    ByteReader n(normals_block);
    const uint32_t normal_bytes = n.get<uint32_t>("coded bytes");
    if (4 + normal_bytes + padding_to_4(normal_bytes) != normals_block.size())
      throw DecodeError("compressed normals: " + std::to_string(normal_bytes) + " coded bytes in a block of " + std::to_string(normals_block.size()));
    if (meshopt_decodeVertexBuffer(octahedral_.data(), v, kNormalVertexBytes, n.here(), normal_bytes) != 0)
      throw DecodeError("compressed normals: the vertex codec refused the data");
    meshopt_decodeFilterOct(octahedral_.data(), v, kNormalVertexBytes);
    // The filter leaves unit vectors rounded to 8 bits a component: unit again here.
    for (size_t i = 0; i < v; ++i) {
      const float x = octahedral_[4 * i], y = octahedral_[4 * i + 1], z = octahedral_[4 * i + 2];
      const float length = std::sqrt(x * x + y * y + z * z);
      const float scale = length > 0.0f ? 1.0f / length : 0.0f;
      float* out = &normals[3 * size_t{order_[i]}];
      out[0] = x * scale, out[1] = y * scale, out[2] = z * scale;
    }
  }
  return Result::Decoded;
}

}  // namespace skinstream::subscriber
