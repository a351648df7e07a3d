#pragma once
// Which encoded Frame message a subscriber receives: its protocol version and the frame flags of
// its encoding (normals, quantised, markers, no positions, parameters, compressed; not the flags
// that change from frame to frame, key frame and timecode). The pipeline encodes each frame
// once per key some subscriber holds, and every subscriber of a key shares that message.

#include <array>
#include <cstdint>

#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::server {

using StreamKey = uint32_t;
inline constexpr uint32_t kStreamKeys = 128;
inline constexpr uint32_t kStreamFlagBits = 0x3F;  // frame flags bits 0-5
inline constexpr uint32_t kStreamVersion2 = 0x40;

inline StreamKey stream_key(uint32_t frame_flags, uint16_t version) {
  return (frame_flags & kStreamFlagBits) | (version >= subscriber::kVersion2 ? kStreamVersion2 : 0u);
}
inline uint32_t stream_flags(StreamKey key) { return key & kStreamFlagBits; }
inline uint16_t stream_version(StreamKey key) { return (key & kStreamVersion2) ? subscriber::kVersion2 : subscriber::kVersion1; }

// A set of stream keys (what the subscribers want, what a frame holds).
struct StreamKeySet {
  std::array<uint64_t, 2> bits{};
  bool has(StreamKey key) const { return key < kStreamKeys && ((bits[key >> 6] >> (key & 63)) & 1u); }
  void add(StreamKey key) {
    if (key < kStreamKeys) bits[key >> 6] |= uint64_t{1} << (key & 63);
  }
  void remove(StreamKey key) {
    if (key < kStreamKeys) bits[key >> 6] &= ~(uint64_t{1} << (key & 63));
  }
  bool empty() const { return bits[0] == 0 && bits[1] == 0; }
  // Calls f(key) for every key in the set, in increasing order.
  template <typename F>
  void for_each(F&& f) const {
    for (uint32_t word = 0; word < 2; ++word)
      for (uint64_t b = bits[word]; b != 0; b &= b - 1) f(static_cast<StreamKey>(64 * word + static_cast<uint32_t>(__builtin_ctzll(b))));
  }
};

}  // namespace skinstream::server
