#pragma once
// The subscriber protocol's Packed message (version 2, docs/subscriber-protocol.md): a MeshInfo
// or Model deflated for a subscriber whose Hello asked (kWantPacked). What a renderer is sent
// when it joins is 2.4 MB for the 53,500-vertex body; 60 render nodes restarting together put
// 140 MB on the stage's link in front of the frames of those already watching. Packed, it is
// about 0.84 MB.
//
// Deflate alone takes 2.2 times off; it takes 2.8 once the largest array of each message (the
// faces of MeshInfo, the reference vertices of the Model: 3N 32-bit values right after the
// message's fixed counts) is coded as each value's difference from the value three before it
// (the same corner of the previous face, the same axis of the previous vertex), split into its
// four byte planes. Lossless: the Model's floats come back bit for bit.
//
// The fixed counts stay outside the deflated stream, so a receiver checks them before it
// inflates anything, and the daemon can change MeshInfo's source rate without packing again.

#include <cstdint>
#include <span>
#include <vector>

#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::subscriber {

// The fixed counts at the start of each packable payload, kept as they are.
inline constexpr size_t kPackedMeshInfoHeadBytes = 20;  // V, F, M, P, source rate
inline constexpr size_t kPackedModelHeadBytes = 16;     // V, P, Y, K
// The Packed payload's own fields before the head: packed type, reserved, unpacked size.
inline constexpr size_t kPackedFieldsBytes = 8;
// Where a packed MeshInfo message (header included) keeps the source rate.
inline constexpr size_t kPackedSourceRateOffset = kHeaderBytes + kPackedFieldsBytes + 16;

// The whole Packed message (header included, version 2) of a MeshInfo or Model payload (without
// its header). `level`: zlib's, 1-9. Throws std::invalid_argument for another type or a payload
// shorter than its counts say.
std::vector<unsigned char> encode_packed(MessageType type, std::span<const unsigned char> payload,
                                         int level = 6);

struct Unpacked {
  MessageType type = MessageType::MeshInfo;
  std::vector<unsigned char> payload;  // as the plain message's, without its header
};
// The message a Packed payload holds. DecodeError naming what is wrong: another packed type, an
// unpacked size over `max_payload` or beyond what deflate can make of the bytes sent, a stream
// that does not inflate to exactly that size, or counts that do not fit it.
Unpacked decode_packed(std::span<const unsigned char> payload, uint32_t max_payload = kMaxPayloadBytes);

// The size of the plain message (header included) a whole Packed message says it holds.
size_t plain_message_bytes(std::span<const unsigned char> packed_message);

// A packed MeshInfo message with another source rate (in place; the rate is outside the stream).
void set_packed_source_rate(std::span<unsigned char> packed_mesh_info, float rate_hz);
float packed_source_rate(std::span<const unsigned char> packed_mesh_info);

}  // namespace skinstream::subscriber
