#pragma once
// The subscriber protocol of docs/subscriber-protocol.md (versions 1 and 2), as bytes: how
// skinstreamd publishes meshes to renderers over TCP and WebSocket. Encoders and decoders for
// every message, and an incremental decoder that cuts a TCP byte stream into messages. No
// sockets here. The version 2 position blocks that are coded elsewhere (compressed vertices:
// protocol/subscriber/compressed_vertices.h; deformation parameters: protocol/subscriber/frame_parameters.h)
// travel through encode_frame_with_block() and FrameView as bytes.
//
// Frames are encoded by the daemon 120 times a second into pooled buffers, so encode_frame()
// writes into a caller's span and allocates nothing; the other messages are rare.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "protocol/stream_buffer.h"

namespace skinstream::subscriber {

inline constexpr uint32_t kMagic = 0x46534B53;  // "SKSF"
inline constexpr uint16_t kProtocolVersion = 1;  // what a subscriber speaks unless it says otherwise
inline constexpr uint16_t kVersion1 = 1;
inline constexpr uint16_t kVersion2 = 2;
inline constexpr uint16_t kNewestVersion = kVersion2;
inline constexpr size_t kHeaderBytes = 12;
inline constexpr uint32_t kMaxPayloadBytes = 64u << 20;

// Packed (version 2 only): a MeshInfo or Model deflated (protocol/subscriber/packed_message.h).
enum class MessageType : uint16_t {
  Hello = 1,
  MeshInfo = 2,
  Frame = 3,
  Status = 4,
  Ack = 5,
  Model = 6,
  Packed = 7
};
const char* to_string(MessageType type);

// Hello "wants" bits.
inline constexpr uint32_t kWantNormals = 1u << 0;
inline constexpr uint32_t kWantQuantised = 1u << 1;
inline constexpr uint32_t kWantMarkers = 1u << 2;
inline constexpr uint32_t kWantNoMesh = 1u << 3;
// Paced: the subscriber sends Ack for every Frame it takes, and the daemon keeps at most
// kPacedWindow Frames unacknowledged (newer ones wait in its newest-wins queue). Bounds the
// latency of a reader slower than the stream (a browser) to the window instead of whatever the
// socket buffers hold.
inline constexpr uint32_t kWantPaced = 1u << 4;
inline constexpr uint32_t kWantAll = 0x1F;
// Version 2 only. Packed: the subscriber reads MeshInfo and Model as Packed messages, about 2.8
// times fewer bytes when it joins (the daemon may still send them plain).
inline constexpr uint32_t kWantPacked = 1u << 5;
inline constexpr uint32_t kWantAllVersion2 =
    (kWantAll & ~kWantQuantised) | kWantPacked;  // version 2 says the encoding apart

// Version 2: how positions are sent (Hello.encoding, MeshInfo.encoding, Status.encoding).
enum class Encoding : uint32_t { Float = 0, Quantised = 1, Compressed = 2, Parameters = 3 };
inline constexpr uint32_t kEncodingCount = 4;
const char* to_string(Encoding encoding);
// Strings of version 2's Hello (subject, token) are at most this long.
inline constexpr size_t kMaxHelloString = 256;
inline constexpr int kPacedWindow = 2;

// Frame flags.
inline constexpr uint32_t kFrameNormals = 1u << 0;
inline constexpr uint32_t kFrameQuantised = 1u << 1;
inline constexpr uint32_t kFrameMarkers = 1u << 2;
inline constexpr uint32_t kFrameNoPositions = 1u << 3;
// Version 2 only.
inline constexpr uint32_t kFrameParameters = 1u << 4;  // the positions block holds the deformation parameters
inline constexpr uint32_t kFrameCompressed = 1u << 5;  // positions (and normals) coded with the vertex codec
inline constexpr uint32_t kFrameKey = 1u << 6;         // compressed: a key frame
inline constexpr uint32_t kFrameTimecode = 1u << 7;    // the timecode fields hold the source's timecode
inline constexpr uint32_t kFrameFlagsVersion1 = 0xF;
inline constexpr uint32_t kFrameFlagsVersion2 = 0xFF;

// The frame flags a version 1 subscriber with these wants receives (normals need a mesh).
uint32_t frame_flags_for(uint32_t wants, bool has_mesh);
// The same for version 2, whose encoding is separate from its wants: the encoding served (one
// this side can serve, see Hello) and the flags of its frames, without kFrameKey and
// kFrameTimecode, which vary from frame to frame.
uint32_t frame_flags_for(uint32_t wants, Encoding served, bool has_mesh);

// Source states in Status messages (same order as server::SourceState).
// Refused (version 2): the daemon refuses this subscriber (unknown subject, wrong token, too many
// subscribers) and closes the connection after the Status; a version 1 subscriber is told
// Disconnected with the same detail.
enum class SourceStateCode : uint32_t { Connecting = 0, Streaming = 1, Disconnected = 2, Finished = 3, Refused = 4 };

// Bytes that do not follow the protocol; the message says which rule was broken.
class DecodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MessageHeader {
  MessageType type = MessageType::Hello;
  uint32_t payload_bytes = 0;
  uint16_t version = kVersion1;
};

struct Hello {
  uint32_t wants = 0;
  uint16_t version = kVersion1;  // the version the subscriber speaks (the header's)
  // Version 2 only (encoded only then): the encoding asked for, as sent (a value this side
  // does not know is kept, to say so in a Status), the subject's name (empty: the first) and
  // the daemon's shared token (empty: none).
  uint32_t encoding = static_cast<uint32_t>(Encoding::Float);
  std::string subject{};
  std::string token{};
};

struct Ack {
  uint32_t frame_number = 0;  // of the Frame taken (informative; every Ack frees one slot)
};

struct MeshInfo {
  uint32_t vertex_count = 0;
  uint32_t marker_count = 0;
  uint32_t part_count = 0;
  float source_rate_hz = 0.0f;
  std::vector<std::array<uint32_t, 3>> faces;
  std::vector<uint8_t> dominant_part;  // one per vertex, 255 = none
  std::vector<std::array<uint32_t, 3>> marker_triangles;
  std::vector<std::string> marker_names;  // marker_count of them
  // Version 2 only.
  std::string subject{};
  Encoding encoding = Encoding::Float;  // served
  // Compressed only (empty otherwise): the vertex coded at each place of the compressed stream.
  std::vector<uint32_t> compressed_order{};
};

// The source's SMPTE timecode of a frame (version 2 Frames, valid with kFrameTimecode).
struct FrameTimecode {
  uint8_t hours = 0, minutes = 0, seconds = 0, frames = 0;
  uint16_t subframe = 0;
  uint16_t subframes_per_frame = 0;
  float rate_hz = 0.0f;
  uint32_t flags = 0;  // bit 0 drop frame, bit 1 field
};
inline constexpr uint32_t kTimecodeDropFrame = 1u << 0;
inline constexpr uint32_t kTimecodeField = 1u << 1;

// The fixed part of a Frame payload.
struct FrameInfo {
  uint32_t frame_number = 0;
  uint32_t flags = 0;
  int64_t source_time_ns = 0;
  int64_t receive_time_ns = 0;
  int64_t publish_time_ns = 0;
  uint32_t vertex_count = 0;
  uint32_t marker_count = 0;
  uint16_t markers_filled = 0;
  uint16_t markers_relabelled = 0;
  uint32_t pipeline_dropped = 0;
  uint32_t subscriber_dropped = 0;
  FrameTimecode timecode;  // version 2 only
};
inline constexpr size_t kFrameInfoBytes = 52;
inline constexpr size_t kTimecodeBytes = 16;
// The fixed part of a Frame payload in this version.
constexpr size_t frame_info_bytes(uint16_t version) { return kFrameInfoBytes + (version >= kVersion2 ? kTimecodeBytes : 0); }
// Where a Frame message (header included) keeps frames_dropped for this subscriber, so one shared
// encoded frame can be sent to every subscriber with only this field changed.
inline constexpr size_t kSubscriberDroppedOffset = kHeaderBytes + 48;
// Where it keeps publish_time_ns: the daemon stamps it after encoding, just before it hands the
// frame to the publishers, so that publish - receive covers all of its processing.
inline constexpr size_t kPublishTimeOffset = kHeaderBytes + 24;

// A decoded frame; quantised data is expanded to floats (origin/step kept for checks).
// Compressed and parameter blocks are kept as bytes (decode them with their own decoders).
struct Frame {
  FrameInfo info;
  std::vector<float> positions;  // 3V, or empty
  std::vector<float> normals;    // 3V, or empty
  std::vector<float> markers;    // 3M, or empty
  std::vector<uint8_t> marker_status;
  std::array<float, 3> origin{}, step{};  // quantised positions only
  std::vector<unsigned char> coded_positions;  // compressed or parameters: the block as sent
  std::vector<unsigned char> coded_normals;    // compressed normals: the block as sent
};

// A Frame payload cut into its blocks, without copying or decoding them (the views point into
// the payload). Each block is as the protocol lays it out, padding included; empty when absent.
struct FrameView {
  FrameInfo info;
  std::span<const unsigned char> positions;  // float, quantised, compressed or parameters (see info.flags)
  std::span<const unsigned char> normals;    // float, quantised or compressed
  std::span<const unsigned char> markers;    // f32[3M]
  std::span<const unsigned char> marker_status;  // u8[M] (unpadded)
};

struct Status {
  SourceStateCode state = SourceStateCode::Connecting;
  float source_rate_hz = 0.0f;
  uint64_t frames_received = 0;
  uint64_t frames_published = 0;
  std::string detail{};
  // Version 2 only.
  std::string subject{};
  bool subject_present = false;  // in the source's latest frames
  Encoding encoding = Encoding::Float;  // served
};

// ---- encoding ----
// Every message but Hello is encoded in the version given (the subscriber's); Hello in its own.
std::vector<unsigned char> encode_hello(const Hello& hello);
std::vector<unsigned char> encode_ack(const Ack& ack, uint16_t version = kVersion1);
std::vector<unsigned char> encode_mesh_info(const MeshInfo& info, uint16_t version = kVersion1);
std::vector<unsigned char> encode_status(const Status& status, uint16_t version = kVersion1);
// The 12-byte header of a message (for messages coded elsewhere, such as Model).
void write_header(MessageType type, uint16_t version, size_t payload_bytes, std::span<unsigned char, kHeaderBytes> out);

// Size of a whole Frame message (header included) for these flags and counts, with float or
// quantised positions (or none).
size_t frame_message_bytes(uint32_t flags, uint32_t vertex_count, uint32_t marker_count, uint16_t version = kVersion1);
// Writes a whole Frame message into `out` (exactly frame_message_bytes() long); allocates nothing.
// positions/normals: 3V floats (ignored when the flags exclude them); markers: 3M floats;
// marker_status: M bytes. Quantised positions use the frame's bounding box (step = extent / 65535).
// Version 2 writes the timecode after the fixed part.
void encode_frame(const FrameInfo& info, std::span<const float> positions, std::span<const float> normals,
                  std::span<const float> markers, std::span<const uint8_t> marker_status, std::span<unsigned char> out,
                  uint16_t version = kVersion1);
// Version 2 frames whose positions (and normals) were coded elsewhere: `blocks` is the positions
// block then the normals block as the protocol lays them out (compressed vertices, or the
// parameters), padded to 4. info.flags must say which (kFrameCompressed or kFrameParameters).
size_t frame_message_bytes_with_block(size_t block_bytes, uint32_t flags, uint32_t marker_count);
void encode_frame_with_block(const FrameInfo& info, std::span<const unsigned char> blocks, std::span<const float> markers,
                             std::span<const uint8_t> marker_status, std::span<unsigned char> out);
// Both versions keep these fields at the same offsets.
void patch_subscriber_dropped(std::span<unsigned char> frame_message, uint32_t dropped);
void patch_publish_time(std::span<unsigned char> frame_message, int64_t publish_time_ns);

// ---- decoding (each throws DecodeError naming what is wrong) ----
// Accepts versions 1 and 2 (Model only in version 2).
MessageHeader decode_header(std::span<const unsigned char> bytes, uint32_t max_payload = kMaxPayloadBytes);
Hello decode_hello(std::span<const unsigned char> payload, uint16_t version = kVersion1);
Ack decode_ack(std::span<const unsigned char> payload);
// What a subscriber takes of a MeshInfo, checked before anything is made for it: a daemon (or
// something posing as one) can announce 67 million vertices in a 64 MiB message, or 8 million
// empty marker names, and a client that sized its buffers from them took 3-4 GB.
struct MeshInfoLimits {
  uint32_t max_vertices = 4'000'000;
  uint32_t max_markers = 4096;
};
MeshInfo decode_mesh_info(std::span<const unsigned char> payload, uint16_t version = kVersion1, const MeshInfoLimits& limits = {});
Frame decode_frame(std::span<const unsigned char> payload, uint16_t version = kVersion1);
// The payload cut into its blocks, every size checked, nothing copied or allocated.
FrameView view_frame(std::span<const unsigned char> payload, uint16_t version = kVersion1);
// view_frame's checks, only the FrameInfo (for a reader that wants the numbers, not the mesh,
// such as skinstream-bench).
FrameInfo decode_frame_info(std::span<const unsigned char> payload, uint16_t version = kVersion1);
Status decode_status(std::span<const unsigned char> payload, uint16_t version = kVersion1);

struct RawMessage {
  MessageType type = MessageType::Hello;
  std::span<const unsigned char> payload;  // valid until the next feed() or prepare()
  uint16_t version = kVersion1;
};

// Cuts a byte stream into messages. After a DecodeError the stream is unusable (close it).
class StreamDecoder {
 public:
  explicit StreamDecoder(uint32_t max_payload = kMaxPayloadBytes) : max_payload_(max_payload) {}
  void feed(std::span<const unsigned char> bytes) { stream_.feed(bytes); }
  // Reading straight into the decoder, without a copy: prepare() gives room for at least
  // `bytes` more, the socket reads into it, commit() says how many it wrote.
  std::span<unsigned char> prepare(size_t bytes) { return stream_.prepare(bytes); }
  void commit(size_t bytes) { stream_.commit(bytes); }
  // The next complete message, or nullopt when more bytes are needed. Throws DecodeError.
  std::optional<RawMessage> next();
  size_t buffered() const { return stream_.buffered(); }

 private:
  uint32_t max_payload_;
  StreamBuffer stream_;
};

}  // namespace skinstream::subscriber
