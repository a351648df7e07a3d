#pragma once
// The subscriber protocol of docs/subscriber-protocol.md (version 1), as bytes: how skinstreamd
// publishes meshes to renderers over TCP and WebSocket. Encoders and decoders for every message,
// and an incremental decoder that cuts a TCP byte stream into messages. No sockets here.
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

namespace skinstream::subscriber {

inline constexpr uint32_t kMagic = 0x46534B53;  // "SKSF"
inline constexpr uint16_t kProtocolVersion = 1;
inline constexpr size_t kHeaderBytes = 12;
inline constexpr uint32_t kMaxPayloadBytes = 64u << 20;

enum class MessageType : uint16_t { Hello = 1, MeshInfo = 2, Frame = 3, Status = 4, Ack = 5 };
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
inline constexpr int kPacedWindow = 2;

// Frame flags.
inline constexpr uint32_t kFrameNormals = 1u << 0;
inline constexpr uint32_t kFrameQuantised = 1u << 1;
inline constexpr uint32_t kFrameMarkers = 1u << 2;
inline constexpr uint32_t kFrameNoPositions = 1u << 3;

// The frame flags a subscriber with these wants receives (normals need a mesh).
uint32_t frame_flags_for(uint32_t wants, bool has_mesh);

// Source states in Status messages (same order as server::SourceState).
enum class SourceStateCode : uint32_t { Connecting = 0, Streaming = 1, Disconnected = 2, Finished = 3 };

// Bytes that do not follow the protocol; the message says which rule was broken.
class DecodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MessageHeader {
  MessageType type = MessageType::Hello;
  uint32_t payload_bytes = 0;
};

struct Hello {
  uint32_t wants = 0;
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
};

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
};
inline constexpr size_t kFrameInfoBytes = 52;
// Where a Frame message (header included) keeps frames_dropped for this subscriber, so one shared
// encoded frame can be sent to every subscriber with only this field changed.
inline constexpr size_t kSubscriberDroppedOffset = kHeaderBytes + 48;
// Where it keeps publish_time_ns: the daemon stamps it after encoding, just before it hands the
// frame to the publishers, so that publish - receive covers all of its processing.
inline constexpr size_t kPublishTimeOffset = kHeaderBytes + 24;

// A decoded frame; quantised data is expanded to floats (origin/step kept for checks).
struct Frame {
  FrameInfo info;
  std::vector<float> positions;  // 3V, or empty
  std::vector<float> normals;    // 3V, or empty
  std::vector<float> markers;    // 3M, or empty
  std::vector<uint8_t> marker_status;
  std::array<float, 3> origin{}, step{};  // quantised positions only
};

struct Status {
  SourceStateCode state = SourceStateCode::Connecting;
  float source_rate_hz = 0.0f;
  uint64_t frames_received = 0;
  uint64_t frames_published = 0;
  std::string detail;
};

// ---- encoding ----
std::vector<unsigned char> encode_hello(const Hello& hello);
std::vector<unsigned char> encode_ack(const Ack& ack);
std::vector<unsigned char> encode_mesh_info(const MeshInfo& info);
std::vector<unsigned char> encode_status(const Status& status);

// Size of a whole Frame message (header included) for these flags and counts.
size_t frame_message_bytes(uint32_t flags, uint32_t vertex_count, uint32_t marker_count);
// Writes a whole Frame message into `out` (exactly frame_message_bytes() long); allocates nothing.
// positions/normals: 3V floats (ignored when the flags exclude them); markers: 3M floats;
// marker_status: M bytes. Quantised positions use the frame's bounding box (step = extent / 65535).
void encode_frame(const FrameInfo& info, std::span<const float> positions, std::span<const float> normals,
                  std::span<const float> markers, std::span<const uint8_t> marker_status, std::span<unsigned char> out);
void patch_subscriber_dropped(std::span<unsigned char> frame_message, uint32_t dropped);
void patch_publish_time(std::span<unsigned char> frame_message, int64_t publish_time_ns);

// ---- decoding (each throws DecodeError naming what is wrong) ----
MessageHeader decode_header(std::span<const unsigned char> bytes, uint32_t max_payload = kMaxPayloadBytes);
Hello decode_hello(std::span<const unsigned char> payload);
Ack decode_ack(std::span<const unsigned char> payload);
MeshInfo decode_mesh_info(std::span<const unsigned char> payload);
Frame decode_frame(std::span<const unsigned char> payload);
// decode_frame's checks of the fixed part and of the sizes, but the arrays are not read (nor
// their marker status values checked): only the FrameInfo, nothing copied or allocated (for a
// reader that wants the numbers, not the mesh, such as skinstream-bench).
FrameInfo decode_frame_info(std::span<const unsigned char> payload);
Status decode_status(std::span<const unsigned char> payload);

struct RawMessage {
  MessageType type = MessageType::Hello;
  std::span<const unsigned char> payload;  // valid until the next feed() or prepare()
};

// Cuts a byte stream into messages. After a DecodeError the stream is unusable (close it).
class StreamDecoder {
 public:
  explicit StreamDecoder(uint32_t max_payload = kMaxPayloadBytes) : max_payload_(max_payload) {}
  void feed(std::span<const unsigned char> bytes);
  // Reading straight into the decoder, without a copy: prepare() gives room for at least
  // `bytes` more, the socket reads into it, commit() says how many it wrote.
  std::span<unsigned char> prepare(size_t bytes);
  void commit(size_t bytes);
  // The next complete message, or nullopt when more bytes are needed. Throws DecodeError.
  std::optional<RawMessage> next();
  size_t buffered() const { return filled_ - consumed_; }

 private:
  uint32_t max_payload_;
  std::vector<unsigned char> buffer_;  // storage; [consumed_, filled_) is not yet cut
  size_t filled_ = 0;
  size_t consumed_ = 0;
};

}  // namespace skinstream::subscriber
