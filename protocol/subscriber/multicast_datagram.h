#pragma once
// The multicast form of the parameter stream (docs/subscriber-protocol.md, "Multicast"): each
// frame's version 2 Frame message of the parameter encoding cut into UDP datagrams of at most
// kMaxDatagramBytes, so no datagram is fragmented by IP on an Ethernet link. Each datagram is a
// 28-byte header and one fragment of the message. No sockets here.
//
// Fragment i of a message of M bytes cut into n holds bytes [i*S, min((i+1)*S, M)) with
// S = ceil(M / n): a receiver checks every fragment's place and size from the header alone.
// With a key (protocol/subscriber/datagram_authentication.h), the header's flags say so and a 32-byte
// HMAC-SHA-256 of the header and the fragment follows the fragment; the fragments are then at
// most kMaxAuthenticatedFragmentBytes, so the datagram stays within kMaxDatagramBytes.
//
// The offer (docs/subscriber-protocol.md, "The offer"): what a joining receiver needs first
// (the packed MeshInfo and Model) sent round and round to the group's next port, cut by the same
// rule into at most kMaxOfferFragments datagrams whose header has the offer flag.

#include <cstddef>
#include <cstdint>
#include <span>

#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::subscriber {

inline constexpr uint32_t kDatagramMagic = 0x4D534B53;  // "SKSM"
inline constexpr uint16_t kDatagramVersion = 1;
inline constexpr size_t kDatagramHeaderBytes = 28;
inline constexpr size_t kMaxDatagramBytes = 1400;  // UDP payload: 1500-byte MTU, less IPv4/IPv6, UDP and room for tunnels
inline constexpr size_t kMaxFragmentBytes = kMaxDatagramBytes - kDatagramHeaderBytes;
inline constexpr size_t kDatagramTrailerBytes = 32;  // the HMAC-SHA-256 tag of an authenticated datagram
inline constexpr size_t kMaxAuthenticatedFragmentBytes = kMaxFragmentBytes - kDatagramTrailerBytes;
inline constexpr uint16_t kMaxFragments = 64;  // a message of at most 64 x 1372 bytes (87,808)
inline constexpr size_t kMaxDatagramMessageBytes = kMaxFragments * kMaxFragmentBytes;
inline constexpr size_t kMaxAuthenticatedMessageBytes = kMaxFragments * kMaxAuthenticatedFragmentBytes;
inline constexpr uint16_t kDatagramAuthenticated = 1u << 0;  // header flags: a tag follows the fragment
inline constexpr uint16_t kDatagramOffer = 1u << 1;   // header flags: a fragment of the offer, not of a frame
inline constexpr uint16_t kMaxOfferFragments = 4096;  // an offer of at most 4,096 x 1,372 bytes (5.6 MB)

struct DatagramHeader {
  uint32_t stream_id = 0;      // the subject's stream (the daemon's subject index)
  uint32_t model_id = 0;       // CRC-32 of the Model message payload these parameters fit
  uint32_t sequence = 0;       // the stream's frame counter: +1 per frame sent
  uint16_t index = 0;          // of this fragment, < count
  uint16_t count = 0;          // fragments of the message, 1-kMaxFragments
  uint32_t message_bytes = 0;  // the whole message's size
  bool authenticated = false;  // a tag follows the fragment
  bool offer = false;          // a fragment of the offer (sequence: the offer's edition)
};

// The fragments a message of this size is cut into; 0 when it is too large to send (more than
// max_fragments fragments: for a frame kMaxDatagramMessageBytes, or kMaxAuthenticatedMessageBytes
// with a tag) or empty.
uint16_t fragment_count(size_t message_bytes, bool authenticated = false,
                        uint16_t max_fragments = kMaxFragments);
// Where fragment `index` of a message cut into `count` starts, and its size (the rule above).
size_t fragment_offset(size_t message_bytes, uint16_t count, uint16_t index);
size_t fragment_bytes(size_t message_bytes, uint16_t count, uint16_t index);

void encode_datagram_header(const DatagramHeader& header, std::span<unsigned char, kDatagramHeaderBytes> out);
// Reads and checks a datagram's header against its size: magic, version, reserved bits,
// index < count <= kMaxFragments (kMaxOfferFragments for the offer), a message size the count can carry with
// no empty fragment, and the datagram exactly the header plus its fragment (and its tag, when authenticated).
// Throws DecodeError naming the rule. The tag is not checked here (DatagramReassembler does).
DatagramHeader decode_datagram_header(std::span<const unsigned char> datagram);
// The model id of a Model message payload (the bytes after its 12-byte header).
uint32_t model_id_of(std::span<const unsigned char> model_payload);

}  // namespace skinstream::subscriber
