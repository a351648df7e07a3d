#pragma once
// The compressed encoding of a version 2 Frame's positions and normals
// (docs/subscriber-protocol.md): positions quantised to 16 bits on a grid fixed from one key
// frame to the next, key frames coded as they are and the frames between as their difference
// from the key, both with meshoptimizer's vertex codec; normals as 8-bit octahedral vectors,
// every frame on its own. The codec itself is lossless on the quantised values, so positions
// come back within half a grid step (about 0.02 mm on a body) and normals within 1.5 degrees.
//
// The daemon keeps one encoder per subject and codes each frame once, whoever subscribes; a
// subscriber keeps one decoder, which must see a frame's key before it can decode the frame.

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

namespace skinstream::subscriber {

struct CompressedBlocks {
  size_t positions_bytes = 0;  // the positions block (padded), first in the output
  size_t normals_bytes = 0;    // the normals block (padded) after it; 0 without normals
  bool key = false;
};

// The order the codec reads the vertices in: each vertex after a near neighbour in space, so that
// the codec's differences between consecutive vertices are small (MeshInfo sends it to
// compressed subscribers). From the reference pose; order[i] is the vertex coded i-th.
std::vector<uint32_t> compressed_vertex_order(std::span<const float> reference_positions);

class CompressedVertexEncoder {
 public:
  // A key frame at least every `key_interval` frames. The key's grid reaches `margin_mm` beyond
  // the key frame's bounding box, so the body can move that far before a key comes early.
  // `order`: the vertices' coding order (a permutation of 0..V-1; empty: their own order).
  CompressedVertexEncoder(int vertex_count, std::vector<uint32_t> order = {}, int key_interval = 10, float margin_mm = 250.0f);

  // The most the blocks can take (size the output once with this).
  size_t max_bytes(bool normals) const;
  // Codes one frame into `out` (at least max_bytes long): a key frame when one is due, when a
  // position leaves the key's grid, or when one was requested; otherwise a delta. Allocates
  // nothing. positions: 3V floats; normals: 3V floats or empty.
  CompressedBlocks encode(uint32_t frame_number, std::span<const float> positions, std::span<const float> normals,
                          std::span<unsigned char> out);
  // Any thread: the next frame becomes a key frame (a subscriber joined and would otherwise wait
  // for the next one).
  void request_key() { key_requested_.store(true, std::memory_order_relaxed); }
  int vertex_count() const { return vertex_count_; }

 private:
  size_t encode_positions(uint32_t frame_number, std::span<const float> positions, bool& key, unsigned char* out);
  size_t encode_normals(std::span<const float> normals, unsigned char* out);

  int vertex_count_;
  std::vector<uint32_t> order_;
  int key_interval_;
  float margin_mm_;
  std::vector<uint16_t> key_q_;      // the key frame's grid positions, 4 per vertex (x y z 0)
  std::vector<uint16_t> vertices_;   // this frame's, 4 per vertex, what the codec reads
  std::vector<float> octahedral_in_;  // normals as x y z 0, for the octahedral filter
  std::vector<int8_t> octahedral_;   // 4 per vertex
  float origin_[3] = {0, 0, 0}, step_[3] = {0, 0, 0};
  uint32_t key_frame_number_ = 0;
  int since_key_ = -1;  // frames coded since the key; -1: no key yet
  std::atomic<bool> key_requested_{false};
};

class CompressedVertexDecoder {
 public:
  // `order` as the encoder's (MeshInfo's compressed vertex order); throws std::invalid_argument
  // when it is not a permutation of 0..vertex_count-1.
  CompressedVertexDecoder(int vertex_count, std::vector<uint32_t> order = {});

  enum class Result { Decoded, NeedsKey };
  // Decodes a frame's blocks (FrameView::positions and ::normals) into 3V floats each (normals
  // may be empty when not wanted or not sent). NeedsKey: a delta of a key this decoder has not
  // seen (it joined late, or the key gave way); skip until a key frame. Throws DecodeError on
  // bytes that do not decode.
  Result decode(std::span<const unsigned char> positions_block, std::span<const unsigned char> normals_block, bool key,
                std::span<float> positions, std::span<float> normals);
  // The key frame number the last key frame had (valid once one was decoded).
  uint32_t key_frame_number() const { return key_frame_number_; }

 private:
  int vertex_count_;
  std::vector<uint32_t> order_;
  std::vector<uint16_t> key_q_;
  std::vector<uint16_t> vertices_;
  std::vector<int8_t> octahedral_;
  float origin_[3] = {0, 0, 0}, step_[3] = {0, 0, 0};
  uint32_t key_frame_number_ = 0;
  bool has_key_ = false;
};

}  // namespace skinstream::subscriber
