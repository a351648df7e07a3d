#include "protocol/subscriber/subscriber_stream.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"
#include "protocol/span_writer.h"
#include "protocol/subscriber/frame_quantisation.h"

namespace skinstream::subscriber {
namespace {

void put_header(SpanWriter& w, MessageType type, size_t payload, uint16_t version) {
  w.put<uint32_t>(kMagic);
  w.put<uint16_t>(version);
  w.put<uint16_t>(static_cast<uint16_t>(type));
  w.put<uint32_t>(static_cast<uint32_t>(payload));
}

// Messages other than Frame: payload built first, then the header in front.
std::vector<unsigned char> with_header(MessageType type, const ByteWriter& payload, uint16_t version) {
  std::vector<unsigned char> message(kHeaderBytes + payload.bytes().size());
  SpanWriter w(message);
  put_header(w, type, payload.bytes().size(), version);
  std::copy(payload.bytes().begin(), payload.bytes().end(), w.reserve(payload.bytes().size()));
  return message;
}

// A string as u16 length + bytes, cut at `limit` bytes.
void put_short_string(ByteWriter& w, const std::string& s, size_t limit = std::numeric_limits<uint16_t>::max()) {
  const size_t n = std::min(s.size(), limit);
  w.put<uint16_t>(static_cast<uint16_t>(n));
  w.put_bytes(s.data(), n);
}

// Empty once the reader failed.
std::string get_short_string(ByteReader& r, const char* what, size_t limit = std::numeric_limits<uint16_t>::max()) {
  const uint16_t n = r.get<uint16_t>(what);
  if (n > limit) throw DecodeError(std::string(what) + " of " + std::to_string(n) + " bytes exceeds " + std::to_string(limit));
  const std::span<const unsigned char> bytes = r.take(n, what);
  return std::string(bytes.begin(), bytes.end());
}

Encoding encoding_of(uint32_t value, const char* what) {
  if (value >= kEncodingCount) throw DecodeError(std::string(what) + ": unknown encoding " + std::to_string(value));
  return static_cast<Encoding>(value);
}

void check_version(uint16_t version) {
  if (version != kVersion1 && version != kVersion2) throw std::invalid_argument("subscriber protocol version " + std::to_string(version));
}

// Runs a payload decoder, turning a read past the end into a DecodeError naming the message and
// the field. The decoder checks r.ok() before judging values read after a failure (zeros).
template <typename F>
auto decode_payload(const char* what, std::span<const unsigned char> payload, F&& body) {
  ByteReader r(payload);
  auto result = body(r);
  if (!r.ok()) throw DecodeError(std::string(what) + ": " + r.error().message());
  if (r.remaining() != 0)
    throw DecodeError(std::string(what) + ": " + std::to_string(r.remaining()) +
                      " bytes left over after the message");
  return result;
}

// Only after the frame's sizes were checked against the payload (read_frame_info), so `count`
// never allocates more than the payload holds.
void get_floats(ByteReader& r, std::vector<float>& out, size_t count, const char* what) {
  out.resize(count);
  r.get_array(out.data(), count, what);
}

}  // namespace

const char* to_string(MessageType type) {
  switch (type) {
    case MessageType::Hello: return "Hello";
    case MessageType::Ack: return "Ack";
    case MessageType::MeshInfo: return "MeshInfo";
    case MessageType::Frame: return "Frame";
    case MessageType::Status: return "Status";
    case MessageType::Model: return "Model";
    case MessageType::Packed:
      return "Packed";
  }
  return "unknown";
}

const char* to_string(Encoding encoding) {
  switch (encoding) {
    case Encoding::Float: return "float";
    case Encoding::Quantised: return "quantised";
    case Encoding::Compressed: return "compressed";
    case Encoding::Parameters: return "parameters";
  }
  return "unknown";
}

uint32_t frame_flags_for(uint32_t wants, bool has_mesh) {
  const bool positions = has_mesh && !(wants & kWantNoMesh);
  uint32_t flags = 0;
  if (!positions) flags |= kFrameNoPositions;
  if (positions && (wants & kWantNormals)) flags |= kFrameNormals;
  if (positions && (wants & kWantQuantised)) flags |= kFrameQuantised;
  if (wants & kWantMarkers) flags |= kFrameMarkers;
  return flags;
}

uint32_t frame_flags_for(uint32_t wants, Encoding served, bool has_mesh) {
  const bool positions = has_mesh && !(wants & kWantNoMesh);
  uint32_t flags = 0;
  if (!positions) flags |= kFrameNoPositions;
  if (positions && served == Encoding::Parameters) flags |= kFrameParameters;  // normals: the subscriber's
  if (positions && served != Encoding::Parameters && (wants & kWantNormals)) flags |= kFrameNormals;
  if (positions && served == Encoding::Quantised) flags |= kFrameQuantised;
  if (positions && served == Encoding::Compressed) flags |= kFrameCompressed;
  if (wants & kWantMarkers) flags |= kFrameMarkers;
  return flags;
}

std::vector<unsigned char> encode_hello(const Hello& hello) {
  check_version(hello.version);
  ByteWriter p;
  p.put<uint32_t>(hello.wants);
  if (hello.version >= kVersion2) {
    p.put<uint32_t>(hello.encoding);
    put_short_string(p, hello.subject, kMaxHelloString);
    put_short_string(p, hello.token, kMaxHelloString);
  }
  return with_header(MessageType::Hello, p, hello.version);
}

std::vector<unsigned char> encode_ack(const Ack& ack, uint16_t version) {
  check_version(version);
  ByteWriter p;
  p.put<uint32_t>(ack.frame_number);
  return with_header(MessageType::Ack, p, version);
}

void write_header(MessageType type, uint16_t version, size_t payload_bytes, std::span<unsigned char, kHeaderBytes> out) {
  check_version(version);
  SpanWriter w(out);
  put_header(w, type, payload_bytes, version);
}

std::vector<unsigned char> encode_mesh_info(const MeshInfo& info, uint16_t version) {
  check_version(version);
  ByteWriter p;
  p.put<uint32_t>(info.vertex_count);
  p.put<uint32_t>(static_cast<uint32_t>(info.faces.size()));
  p.put<uint32_t>(info.marker_count);
  p.put<uint32_t>(info.part_count);
  p.put<float>(info.source_rate_hz);
  for (const auto& f : info.faces)
    for (uint32_t v : f) p.put<uint32_t>(v);
  for (uint32_t v = 0; v < info.vertex_count; ++v)
    p.put<uint8_t>(v < info.dominant_part.size() ? info.dominant_part[v] : uint8_t{255});
  p.put<uint32_t>(static_cast<uint32_t>(info.marker_triangles.size()));
  for (const auto& t : info.marker_triangles)
    for (uint32_t m : t) p.put<uint32_t>(m);
  for (const std::string& name : info.marker_names) put_short_string(p, name);
  if (version >= kVersion2) {
    put_short_string(p, info.subject);
    p.put<uint32_t>(static_cast<uint32_t>(info.encoding));
    p.put<uint32_t>(static_cast<uint32_t>(info.compressed_order.size()));
    p.put_bytes(info.compressed_order.data(), info.compressed_order.size() * sizeof(uint32_t));
  }
  return with_header(MessageType::MeshInfo, p, version);
}

std::vector<unsigned char> encode_status(const Status& status, uint16_t version) {
  check_version(version);
  ByteWriter p;
  // Version 1 has no "refused": its subscriber is told the source is disconnected, and why.
  const bool refused_in_v1 = version < kVersion2 && status.state == SourceStateCode::Refused;
  p.put<uint32_t>(static_cast<uint32_t>(refused_in_v1 ? SourceStateCode::Disconnected : status.state));
  p.put<float>(status.source_rate_hz);
  p.put<uint64_t>(status.frames_received);
  p.put<uint64_t>(status.frames_published);
  put_short_string(p, status.detail);
  if (version >= kVersion2) {
    put_short_string(p, status.subject);
    p.put<uint32_t>(status.subject_present ? 1u : 0u);
    p.put<uint32_t>(static_cast<uint32_t>(status.encoding));
  }
  return with_header(MessageType::Status, p, version);
}

size_t frame_message_bytes(uint32_t flags, uint32_t vertex_count, uint32_t marker_count, uint16_t version) {
  size_t bytes = kHeaderBytes + frame_info_bytes(version);
  const size_t v3 = 3 * static_cast<size_t>(vertex_count);
  const bool quantised = flags & kFrameQuantised;
  // Quantised blocks are padded to 4 bytes so the floats after them stay aligned (JS typed arrays).
  if (!(flags & kFrameNoPositions)) bytes += quantised ? 24 + 2 * v3 + padding_to_4(2 * v3) : 4 * v3;
  if (flags & kFrameNormals) bytes += quantised ? 2 * v3 + padding_to_4(2 * v3) : 4 * v3;
  if (flags & kFrameMarkers) bytes += 12 * static_cast<size_t>(marker_count) + marker_count + padding_to_4(marker_count);
  return bytes;
}

namespace {

// The header, the fixed part and (version 2) the timecode.
void write_frame_start(SpanWriter& w, const FrameInfo& info, size_t total, uint16_t version) {
  put_header(w, MessageType::Frame, total - kHeaderBytes, version);
  w.put<uint32_t>(info.frame_number);
  w.put<uint32_t>(info.flags);
  w.put<int64_t>(info.source_time_ns);
  w.put<int64_t>(info.receive_time_ns);
  w.put<int64_t>(info.publish_time_ns);
  w.put<uint32_t>(info.vertex_count);
  w.put<uint32_t>(info.marker_count);
  w.put<uint16_t>(info.markers_filled);
  w.put<uint16_t>(info.markers_relabelled);
  w.put<uint32_t>(info.pipeline_dropped);
  w.put<uint32_t>(info.subscriber_dropped);
  if (version < kVersion2) return;
  const FrameTimecode& t = info.timecode;
  w.put<uint8_t>(t.hours);
  w.put<uint8_t>(t.minutes);
  w.put<uint8_t>(t.seconds);
  w.put<uint8_t>(t.frames);
  w.put<uint16_t>(t.subframe);
  w.put<uint16_t>(t.subframes_per_frame);
  w.put<float>(t.rate_hz);
  w.put<uint32_t>(t.flags);
}

void write_markers(SpanWriter& w, const FrameInfo& info, std::span<const float> markers, std::span<const uint8_t> marker_status) {
  w.put_array<float>(markers.first(3 * size_t{info.marker_count}));
  std::memcpy(w.reserve(info.marker_count), marker_status.data(), info.marker_count);
  w.zeros(padding_to_4(info.marker_count));
}

size_t marker_block_bytes(uint32_t marker_count) { return 12 * size_t{marker_count} + marker_count + padding_to_4(marker_count); }

}  // namespace

void encode_frame(const FrameInfo& in, std::span<const float> positions, std::span<const float> normals,
                  std::span<const float> markers, std::span<const uint8_t> marker_status, std::span<unsigned char> out,
                  uint16_t version) {
  check_version(version);
  FrameInfo info = in;
  if (info.flags & ~(version >= kVersion2 ? kFrameFlagsVersion2 : kFrameFlagsVersion1) ||
      (info.flags & (kFrameParameters | kFrameCompressed | kFrameKey)))
    throw std::invalid_argument("encode_frame: flags " + std::to_string(info.flags) + " are not a float or quantised frame of this version");
  const bool has_positions = !(info.flags & kFrameNoPositions);
  const bool has_normals = info.flags & kFrameNormals;
  const bool has_markers = info.flags & kFrameMarkers;
  const bool quantised = info.flags & kFrameQuantised;
  if (!has_positions) info.vertex_count = 0;
  if (!has_markers) info.marker_count = 0;
  const size_t v3 = 3 * static_cast<size_t>(info.vertex_count);
  const size_t total = frame_message_bytes(info.flags, info.vertex_count, info.marker_count, version);
  if (out.size() != total || (has_positions && positions.size() < v3) || (has_normals && normals.size() < v3) ||
      (has_markers && (markers.size() < 3 * size_t{info.marker_count} || marker_status.size() < info.marker_count)))
    throw std::invalid_argument("encode_frame: buffer sizes do not match the frame's counts");

  SpanWriter w(out);
  write_frame_start(w, info, total, version);

  if (has_positions && !quantised) {
    w.put_array<float>(positions.first(v3));
  } else if (has_positions) {
    const QuantisationBox box = quantisation_box(positions.first(v3));
    for (int a = 0; a < 3; ++a) w.put<float>(box.lo[a]);
    for (int a = 0; a < 3; ++a) w.put<float>(box.step[a]);
    quantise_positions(positions.first(v3), box, w.reserve(2 * v3));
    w.zeros(padding_to_4(2 * v3));
  }
  if (has_normals && !quantised) {
    w.put_array<float>(normals.first(v3));
  } else if (has_normals) {
    quantise_normals(normals.first(v3), w.reserve(2 * v3));
    w.zeros(padding_to_4(2 * v3));
  }
  if (has_markers) write_markers(w, info, markers, marker_status);
}

size_t frame_message_bytes_with_block(size_t block_bytes, uint32_t flags, uint32_t marker_count) {
  return kHeaderBytes + frame_info_bytes(kVersion2) + block_bytes + ((flags & kFrameMarkers) ? marker_block_bytes(marker_count) : 0);
}

void encode_frame_with_block(const FrameInfo& in, std::span<const unsigned char> blocks, std::span<const float> markers,
                             std::span<const uint8_t> marker_status, std::span<unsigned char> out) {
  FrameInfo info = in;
  const bool coded = (info.flags & kFrameParameters) || (info.flags & kFrameCompressed);
  if ((info.flags & ~kFrameFlagsVersion2) || !coded || (info.flags & (kFrameQuantised | kFrameNoPositions)) ||
      ((info.flags & kFrameParameters) && (info.flags & (kFrameCompressed | kFrameNormals | kFrameKey))) || blocks.size() % 4 != 0)
    throw std::invalid_argument("encode_frame_with_block: flags " + std::to_string(info.flags) +
                                " are not a compressed or parameter frame, or the block is not padded");
  if (info.flags & kFrameParameters) info.vertex_count = 0;
  const bool has_markers = info.flags & kFrameMarkers;
  if (!has_markers) info.marker_count = 0;
  const size_t total = frame_message_bytes_with_block(blocks.size(), info.flags, info.marker_count);
  if (out.size() != total ||
      (has_markers && (markers.size() < 3 * size_t{info.marker_count} || marker_status.size() < info.marker_count)))
    throw std::invalid_argument("encode_frame_with_block: buffer sizes do not match the frame's counts");
  SpanWriter w(out);
  write_frame_start(w, info, total, kVersion2);
  std::memcpy(w.reserve(blocks.size()), blocks.data(), blocks.size());
  if (has_markers) write_markers(w, info, markers, marker_status);
}

void patch_subscriber_dropped(std::span<unsigned char> frame_message, uint32_t dropped) {
  if (frame_message.size() < kSubscriberDroppedOffset + 4) throw std::invalid_argument("patch_subscriber_dropped: not a frame message");
  std::memcpy(frame_message.data() + kSubscriberDroppedOffset, &dropped, 4);
}

void patch_publish_time(std::span<unsigned char> frame_message, int64_t publish_time_ns) {
  if (frame_message.size() < kPublishTimeOffset + 8) throw std::invalid_argument("patch_publish_time: not a frame message");
  std::memcpy(frame_message.data() + kPublishTimeOffset, &publish_time_ns, 8);
}

MessageHeader decode_header(std::span<const unsigned char> bytes, uint32_t max_payload) {
  if (bytes.size() < kHeaderBytes)
    throw DecodeError("message header truncated: " + std::to_string(bytes.size()) + " of 12 bytes");
  ByteReader r(bytes.first(kHeaderBytes));
  const uint32_t magic = r.get<uint32_t>("magic");
  const uint16_t version = r.get<uint16_t>("version");
  const uint16_t type = r.get<uint16_t>("message type");
  const uint32_t payload = r.get<uint32_t>("payload size");
  if (magic != kMagic) throw DecodeError("bad magic (not a skinstream subscriber stream)");
  if (version != kVersion1 && version != kVersion2)
    throw DecodeError("unsupported protocol version " + std::to_string(version) + " (this side speaks 1 and 2)");
  const uint16_t last_type = version >= kVersion2 ? 7 : 5;
  if (type < 1 || type > last_type)
    throw DecodeError("unknown message type " + std::to_string(type) + " in version " + std::to_string(version));
  if (payload > max_payload)
    throw DecodeError("payload of " + std::to_string(payload) + " bytes exceeds the limit of " + std::to_string(max_payload));
  return {static_cast<MessageType>(type), payload, version};
}

Hello decode_hello(std::span<const unsigned char> payload, uint16_t version) {
  return decode_payload("Hello", payload, [version](ByteReader& r) {
    Hello hello;
    hello.version = version;
    hello.wants = r.get<uint32_t>("wants");
    const uint32_t allowed = version >= kVersion2 ? kWantAllVersion2 : kWantAll;
    if (hello.wants & ~allowed) throw DecodeError("Hello: reserved wants bits set (" + std::to_string(hello.wants) + ")");
    if (version >= kVersion2) {
      hello.encoding = r.get<uint32_t>("encoding");  // an unknown one is the daemon's to answer, not an error
      hello.subject = get_short_string(r, "Hello: subject name", kMaxHelloString);
      hello.token = get_short_string(r, "Hello: token", kMaxHelloString);
    }
    return hello;
  });
}

Ack decode_ack(std::span<const unsigned char> payload) {
  return decode_payload("Ack", payload, [](ByteReader& r) { return Ack{r.get<uint32_t>("frame number")}; });
}

MeshInfo decode_mesh_info(std::span<const unsigned char> payload, uint16_t version, const MeshInfoLimits& limits) {
  return decode_payload("MeshInfo", payload, [version, &limits](ByteReader& r) {
    MeshInfo info;
    info.vertex_count = r.get<uint32_t>("vertex count");
    const uint32_t face_count = r.get<uint32_t>("face count");
    info.marker_count = r.get<uint32_t>("marker count");
    info.part_count = r.get<uint32_t>("part count");
    info.source_rate_hz = r.get<float>("source rate");
    if (!r.ok()) return info;
    if (info.vertex_count > limits.max_vertices)
      throw DecodeError("MeshInfo: " + std::to_string(info.vertex_count) + " vertices, more than this subscriber takes (" +
                        std::to_string(limits.max_vertices) + ", its max_vertices)");
    if (info.marker_count > limits.max_markers)
      throw DecodeError("MeshInfo: " + std::to_string(info.marker_count) + " markers, more than this subscriber takes (" +
                        std::to_string(limits.max_markers) + ", its max_markers)");
    if (face_count > r.remaining() / 12 || info.vertex_count > r.remaining())
      throw DecodeError("MeshInfo: vertex or face count exceeds the data left");
    info.faces.resize(face_count);
    for (auto& f : info.faces)
      for (uint32_t& v : f) {
        v = r.get<uint32_t>("face");
        if (r.ok() && v >= info.vertex_count)
          throw DecodeError("MeshInfo: face index " + std::to_string(v) + " out of range");
      }
    info.dominant_part.resize(info.vertex_count);
    r.get_array(info.dominant_part.data(), info.dominant_part.size(), "dominant parts");
    info.marker_triangles.resize(r.get_count(12, "marker triangles"));
    for (auto& t : info.marker_triangles)
      for (uint32_t& m : t) {
        m = r.get<uint32_t>("marker triangle");
        if (r.ok() && m >= info.marker_count)
          throw DecodeError("MeshInfo: marker triangle index " + std::to_string(m) + " out of range");
      }
    if (!r.ok()) return info;
    if (info.marker_count > r.remaining() / 2)
      throw DecodeError("MeshInfo: marker count exceeds the data left");
    info.marker_names.resize(info.marker_count);
    for (std::string& name : info.marker_names) name = get_short_string(r, "marker name");
    if (version >= kVersion2) {
      info.subject = get_short_string(r, "MeshInfo: subject name");
      info.encoding = encoding_of(r.get<uint32_t>("encoding"), "MeshInfo");
      const uint32_t order = r.get<uint32_t>("compressed vertex order");
      if (order != 0 && order != info.vertex_count)
        throw DecodeError("MeshInfo: a compressed vertex order of " + std::to_string(order) + " for " + std::to_string(info.vertex_count) + " vertices");
      if (order > r.remaining() / 4) {
        r.fail("compressed vertex order", 4 * size_t{order});
        return info;
      }
      info.compressed_order.resize(order);
      r.get_array(info.compressed_order.data(), order, "compressed vertex order");
      for (uint32_t v : info.compressed_order)
        if (v >= info.vertex_count) throw DecodeError("MeshInfo: compressed vertex order names vertex " + std::to_string(v));
    }
    return info;
  });
}

namespace {

// The fixed part of a Frame payload (and the version 2 timecode), its flags checked once read
// whole; the reader is left at the first block.
FrameInfo read_frame_info(ByteReader& r, uint16_t version) {
  FrameInfo info;
  info.frame_number = r.get<uint32_t>("frame number");
  info.flags = r.get<uint32_t>("flags");
  info.source_time_ns = r.get<int64_t>("source time");
  info.receive_time_ns = r.get<int64_t>("receive time");
  info.publish_time_ns = r.get<int64_t>("publish time");
  info.vertex_count = r.get<uint32_t>("vertex count");
  info.marker_count = r.get<uint32_t>("marker count");
  info.markers_filled = r.get<uint16_t>("markers filled");
  info.markers_relabelled = r.get<uint16_t>("markers relabelled");
  info.pipeline_dropped = r.get<uint32_t>("pipeline dropped");
  info.subscriber_dropped = r.get<uint32_t>("subscriber dropped");
  if (version >= kVersion2) {
    FrameTimecode& t = info.timecode;
    t.hours = r.get<uint8_t>("timecode hours");
    t.minutes = r.get<uint8_t>("timecode minutes");
    t.seconds = r.get<uint8_t>("timecode seconds");
    t.frames = r.get<uint8_t>("timecode frames");
    t.subframe = r.get<uint16_t>("timecode subframe");
    t.subframes_per_frame = r.get<uint16_t>("timecode subframes per frame");
    t.rate_hz = r.get<float>("timecode rate");
    t.flags = r.get<uint32_t>("timecode flags");
  }
  if (!r.ok()) return info;
  const uint32_t allowed = version >= kVersion2 ? kFrameFlagsVersion2 : kFrameFlagsVersion1;
  if (info.flags & ~allowed) throw DecodeError("Frame: reserved flag bits set (" + std::to_string(info.flags) + ")");
  const bool has_positions = !(info.flags & kFrameNoPositions);
  const int encodings = ((info.flags & kFrameQuantised) != 0) + ((info.flags & kFrameCompressed) != 0) + ((info.flags & kFrameParameters) != 0);
  if (encodings > 1) throw DecodeError("Frame: more than one encoding of the positions");
  if (!has_positions && (info.vertex_count != 0 || encodings != 0)) throw DecodeError("Frame: positions encoded with \"no positions\"");
  if (!has_positions && (info.flags & kFrameNormals)) throw DecodeError("Frame: normals without positions");
  if ((info.flags & kFrameParameters) && (info.flags & kFrameNormals)) throw DecodeError("Frame: normals with parameters");
  if ((info.flags & kFrameParameters) && info.vertex_count != 0) throw DecodeError("Frame: vertex count with parameters");
  if ((info.flags & kFrameKey) && !(info.flags & kFrameCompressed)) throw DecodeError("Frame: key frame flag without compression");
  if (!(info.flags & kFrameMarkers) && info.marker_count != 0) throw DecodeError("Frame: marker count without markers");
  return info;
}

// The next `bytes` of the payload as a block, or a DecodeError naming it.
std::span<const unsigned char> take_block(ByteReader& r, size_t bytes, const char* what) {
  if (bytes > r.remaining())
    throw DecodeError(std::string("Frame: ") + what + " of " + std::to_string(bytes) + " bytes, the payload holds " +
                      std::to_string(r.remaining()));
  return r.take(bytes, what);
}

// A block whose first u32 (at `offset`) counts the coded bytes that follow: its whole size.
size_t counted_block_bytes(const ByteReader& r, size_t offset, const char* what) {
  if (r.remaining() < offset + 4) throw DecodeError(std::string("Frame: ") + what + " truncated");
  ByteReader peek = r;
  peek.skip(offset, what);
  const uint32_t coded = peek.get<uint32_t>(what);
  if (coded > r.remaining()) throw DecodeError(std::string("Frame: ") + what + " says " + std::to_string(coded) + " bytes, more than the payload holds");
  return offset + 4 + coded + padding_to_4(coded);
}

FrameView view_payload(ByteReader& r, uint16_t version) {
  FrameView view;
  view.info = read_frame_info(r, version);
  if (!r.ok()) return view;
  const FrameInfo& info = view.info;
  const size_t v3 = 3 * size_t{info.vertex_count};
  const bool has_positions = !(info.flags & kFrameNoPositions);
  if (info.flags & kFrameParameters) {
    if (r.remaining() < 8) throw DecodeError("Frame: parameters truncated");
    ByteReader peek = r;
    const uint64_t parts = peek.get<uint32_t>("parameter parts"),
                   members = peek.get<uint32_t>("parameter members");
    view.positions = take_block(r, 8 + 160 * parts + 12 * members, "parameters");
  } else if (info.flags & kFrameCompressed) {
    view.positions =
        take_block(r, counted_block_bytes(r, 28, "compressed positions"), "compressed positions");
    if (info.flags & kFrameNormals)
      view.normals = take_block(r, counted_block_bytes(r, 0, "compressed normals"), "compressed normals");
  } else if (has_positions) {
    const bool quantised = info.flags & kFrameQuantised;
    // Checked against the payload before anything is cut, so a corrupt count is named as such.
    const size_t expected = frame_message_bytes(info.flags, info.vertex_count, info.marker_count, version) -
                            kHeaderBytes - frame_info_bytes(version);
    if (expected != r.remaining())
      throw DecodeError("Frame: counts say " + std::to_string(expected) + " bytes of data, the payload holds " +
                        std::to_string(r.remaining()));
    view.positions = take_block(r, quantised ? 24 + 2 * v3 + padding_to_4(2 * v3) : 4 * v3, "positions");
    if (info.flags & kFrameNormals)
      view.normals = take_block(r, quantised ? 2 * v3 + padding_to_4(2 * v3) : 4 * v3, "normals");
  }
  if (info.flags & kFrameMarkers) {
    const size_t m = info.marker_count;
    if (marker_block_bytes(info.marker_count) != r.remaining())
      throw DecodeError("Frame: counts say " + std::to_string(marker_block_bytes(info.marker_count)) +
                        " bytes of markers, the payload holds " + std::to_string(r.remaining()));
    view.markers = take_block(r, 12 * m, "markers");
    view.marker_status = take_block(r, m, "marker status");
    r.skip(padding_to_4(m), "marker padding");
  }
  if (r.remaining() != 0)
    throw DecodeError("Frame: counts say " + std::to_string(r.position()) + " bytes, the payload holds " +
                      std::to_string(r.size()));
  return view;
}

}  // namespace

FrameView view_frame(std::span<const unsigned char> payload, uint16_t version) {
  return decode_payload("Frame", payload, [&](ByteReader& r) { return view_payload(r, version); });
}

FrameInfo decode_frame_info(std::span<const unsigned char> payload, uint16_t version) { return view_frame(payload, version).info; }

Frame decode_frame(std::span<const unsigned char> payload, uint16_t version) {
  const FrameView view = view_frame(payload, version);
  Frame frame;
  frame.info = view.info;
  const FrameInfo& info = frame.info;
  const size_t v3 = 3 * size_t{info.vertex_count};
  const bool quantised = info.flags & kFrameQuantised;
  // The blocks' sizes were checked by view_frame: the reads below cannot fail.
  if ((info.flags & kFrameCompressed) || (info.flags & kFrameParameters)) {
    frame.coded_positions.assign(view.positions.begin(), view.positions.end());
    frame.coded_normals.assign(view.normals.begin(), view.normals.end());
  } else if (quantised) {
    ByteReader r(view.positions);
    r.get_array(frame.origin.data(), 3, "quantisation origin");
    r.get_array(frame.step.data(), 3, "quantisation step");
    frame.positions.resize(v3);
    for (size_t i = 0; i < v3; ++i)
      frame.positions[i] = frame.origin[i % 3] + r.get<uint16_t>("positions") * frame.step[i % 3];
    if (!view.normals.empty()) {
      ByteReader n(view.normals);
      frame.normals.resize(v3);
      for (float& c : frame.normals) c = n.get<int16_t>("normals") / 32767.0f;
    }
  } else {
    ByteReader p(view.positions);
    get_floats(p, frame.positions, view.positions.size() / 4, "positions");
    ByteReader n(view.normals);
    get_floats(n, frame.normals, view.normals.size() / 4, "normals");
    if (frame.positions.size() != v3 || (!frame.normals.empty() && frame.normals.size() != v3))
      throw DecodeError("Frame: block sizes do not match the vertex count");
  }
  ByteReader m(view.markers);
  get_floats(m, frame.markers, view.markers.size() / 4, "markers");
  frame.marker_status.assign(view.marker_status.begin(), view.marker_status.end());
  for (uint8_t s : frame.marker_status)
    if (s > 4) throw DecodeError("Frame: marker status " + std::to_string(s) + " is not one of 0-4");
  return frame;
}

Status decode_status(std::span<const unsigned char> payload, uint16_t version) {
  return decode_payload("Status", payload, [version](ByteReader& r) {
    Status status;
    const uint32_t state = r.get<uint32_t>("source state");
    if (state > (version >= kVersion2 ? 4u : 3u)) throw DecodeError("Status: unknown source state " + std::to_string(state));
    status.state = static_cast<SourceStateCode>(state);
    status.source_rate_hz = r.get<float>("source rate");
    status.frames_received = r.get<uint64_t>("frames received");
    status.frames_published = r.get<uint64_t>("frames published");
    status.detail = get_short_string(r, "Status: detail");
    if (version >= kVersion2) {
      status.subject = get_short_string(r, "Status: subject name");
      const uint32_t present = r.get<uint32_t>("subject presence");
      if (present > 1) throw DecodeError("Status: subject presence " + std::to_string(present) + " is not 0 or 1");
      status.subject_present = present == 1;
      status.encoding = encoding_of(r.get<uint32_t>("encoding"), "Status");
    }
    return status;
  });
}

std::optional<RawMessage> StreamDecoder::next() {
  const std::span<const unsigned char> pending = stream_.unread();
  if (pending.size() < kHeaderBytes) return std::nullopt;
  const MessageHeader header = decode_header(pending, max_payload_);
  if (pending.size() - kHeaderBytes < header.payload_bytes) return std::nullopt;
  stream_.consume(kHeaderBytes + header.payload_bytes);
  return RawMessage{header.type, pending.subspan(kHeaderBytes, header.payload_bytes), header.version};
}

}  // namespace skinstream::subscriber
