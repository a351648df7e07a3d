#include "protocol/subscriber_stream.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "protocol/byte_buffer.h"
#include "protocol/frame_quantisation.h"

namespace skinstream::subscriber {
namespace {

// Writes little-endian values at a cursor in a caller's span (the frame path, no allocation).
// The host's byte order is the protocol's, so values are copied as they are.
static_assert(std::endian::native == std::endian::little, "the protocol is little-endian; a big-endian host must swap");
class SpanWriter {
 public:
  explicit SpanWriter(std::span<unsigned char> out) : out_(out) {}
  template <typename T>
  void put(T value) {
    std::memcpy(out_.data() + pos_, &value, sizeof(T));
    pos_ += sizeof(T);
  }
  // A whole array in one copy: value by value, the compiler must assume each byte written may
  // be the cursor itself and reload it, which made the 640 kB of a mesh's positions a scalar loop.
  void put_floats(std::span<const float> values) {
    if (values.empty()) return;  // its data() may be null, which memcpy must not be given
    std::memcpy(out_.data() + pos_, values.data(), values.size_bytes());
    pos_ += values.size_bytes();
  }
  // The next n bytes, for the caller to fill; the cursor moves past them.
  unsigned char* reserve(size_t n) {
    unsigned char* at = out_.data() + pos_;
    pos_ += n;
    return at;
  }
  void zeros(size_t n) {
    std::memset(out_.data() + pos_, 0, n);
    pos_ += n;
  }
  size_t position() const { return pos_; }

 private:
  std::span<unsigned char> out_;
  size_t pos_ = 0;
};

void put_header(ByteWriter& w, MessageType type, size_t payload) {
  w.put<uint32_t>(kMagic);
  w.put<uint16_t>(kProtocolVersion);
  w.put<uint16_t>(static_cast<uint16_t>(type));
  w.put<uint32_t>(static_cast<uint32_t>(payload));
}

// Messages other than Frame: payload built first, then the header in front.
std::vector<unsigned char> with_header(MessageType type, const ByteWriter& payload) {
  ByteWriter w;
  put_header(w, type, payload.bytes().size());
  w.put_bytes(payload.bytes().data(), payload.bytes().size());
  return std::move(w.bytes());
}

size_t padding_to_4(size_t n) { return (4 - n % 4) % 4; }

// Runs a payload decoder, turning a read past the end into a DecodeError naming the message.
template <typename F>
auto decode_payload(const char* what, std::span<const unsigned char> payload, F&& body) {
  ByteReader r(payload.data(), payload.size());
  try {
    auto result = body(r);
    if (r.remaining() != 0)
      throw DecodeError(std::string(what) + ": " + std::to_string(r.remaining()) + " bytes left over after the message");
    return result;
  } catch (const std::out_of_range& e) {
    throw DecodeError(std::string(what) + ": " + e.what());
  }
}

// Only after the frame's sizes were checked against the payload (read_frame_info), so `count`
// never allocates more than the payload holds.
void get_floats(ByteReader& r, std::vector<float>& out, size_t count) {
  out.resize(count);
  r.get_array(out.data(), count);
}

}  // namespace

const char* to_string(MessageType type) {
  switch (type) {
    case MessageType::Hello: return "Hello";
    case MessageType::Ack: return "Ack";
    case MessageType::MeshInfo: return "MeshInfo";
    case MessageType::Frame: return "Frame";
    case MessageType::Status: return "Status";
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

std::vector<unsigned char> encode_hello(const Hello& hello) {
  ByteWriter p;
  p.put<uint32_t>(hello.wants);
  return with_header(MessageType::Hello, p);
}

std::vector<unsigned char> encode_ack(const Ack& ack) {
  ByteWriter p;
  p.put<uint32_t>(ack.frame_number);
  return with_header(MessageType::Ack, p);
}

std::vector<unsigned char> encode_mesh_info(const MeshInfo& info) {
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
  for (const std::string& name : info.marker_names) {
    const size_t n = std::min<size_t>(name.size(), std::numeric_limits<uint16_t>::max());
    p.put<uint16_t>(static_cast<uint16_t>(n));
    p.put_bytes(name.data(), n);
  }
  return with_header(MessageType::MeshInfo, p);
}

std::vector<unsigned char> encode_status(const Status& status) {
  ByteWriter p;
  p.put<uint32_t>(static_cast<uint32_t>(status.state));
  p.put<float>(status.source_rate_hz);
  p.put<uint64_t>(status.frames_received);
  p.put<uint64_t>(status.frames_published);
  const size_t n = std::min<size_t>(status.detail.size(), std::numeric_limits<uint16_t>::max());
  p.put<uint16_t>(static_cast<uint16_t>(n));
  p.put_bytes(status.detail.data(), n);
  return with_header(MessageType::Status, p);
}

size_t frame_message_bytes(uint32_t flags, uint32_t vertex_count, uint32_t marker_count) {
  size_t bytes = kHeaderBytes + kFrameInfoBytes;
  const size_t v3 = 3 * static_cast<size_t>(vertex_count);
  const bool quantised = flags & kFrameQuantised;
  // Quantised blocks are padded to 4 bytes so the floats after them stay aligned (JS typed arrays).
  if (!(flags & kFrameNoPositions)) bytes += quantised ? 24 + 2 * v3 + padding_to_4(2 * v3) : 4 * v3;
  if (flags & kFrameNormals) bytes += quantised ? 2 * v3 + padding_to_4(2 * v3) : 4 * v3;
  if (flags & kFrameMarkers) bytes += 12 * static_cast<size_t>(marker_count) + marker_count + padding_to_4(marker_count);
  return bytes;
}

void encode_frame(const FrameInfo& in, std::span<const float> positions, std::span<const float> normals,
                  std::span<const float> markers, std::span<const uint8_t> marker_status, std::span<unsigned char> out) {
  FrameInfo info = in;
  const bool has_positions = !(info.flags & kFrameNoPositions);
  const bool has_normals = info.flags & kFrameNormals;
  const bool has_markers = info.flags & kFrameMarkers;
  const bool quantised = info.flags & kFrameQuantised;
  if (!has_positions) info.vertex_count = 0;
  if (!has_markers) info.marker_count = 0;
  const size_t v3 = 3 * static_cast<size_t>(info.vertex_count);
  const size_t total = frame_message_bytes(info.flags, info.vertex_count, info.marker_count);
  if (out.size() != total || (has_positions && positions.size() < v3) || (has_normals && normals.size() < v3) ||
      (has_markers && (markers.size() < 3 * size_t{info.marker_count} || marker_status.size() < info.marker_count)))
    throw std::invalid_argument("encode_frame: buffer sizes do not match the frame's counts");

  SpanWriter w(out);
  w.put<uint32_t>(kMagic);
  w.put<uint16_t>(kProtocolVersion);
  w.put<uint16_t>(static_cast<uint16_t>(MessageType::Frame));
  w.put<uint32_t>(static_cast<uint32_t>(total - kHeaderBytes));
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

  if (has_positions && !quantised) {
    w.put_floats(positions.first(v3));
  } else if (has_positions) {
    const QuantisationBox box = quantisation_box(positions.first(v3));
    for (int a = 0; a < 3; ++a) w.put<float>(box.lo[a]);
    for (int a = 0; a < 3; ++a) w.put<float>(box.step[a]);
    quantise_positions(positions.first(v3), box, w.reserve(2 * v3));
    w.zeros(padding_to_4(2 * v3));
  }
  if (has_normals && !quantised) {
    w.put_floats(normals.first(v3));
  } else if (has_normals) {
    quantise_normals(normals.first(v3), w.reserve(2 * v3));
    w.zeros(padding_to_4(2 * v3));
  }
  if (has_markers) {
    w.put_floats(markers.first(3 * size_t{info.marker_count}));
    for (uint32_t m = 0; m < info.marker_count; ++m) w.put<uint8_t>(marker_status[m]);
    w.zeros(padding_to_4(info.marker_count));
  }
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
  ByteReader r(bytes.data(), kHeaderBytes);
  const uint32_t magic = r.get<uint32_t>();
  const uint16_t version = r.get<uint16_t>();
  const uint16_t type = r.get<uint16_t>();
  const uint32_t payload = r.get<uint32_t>();
  if (magic != kMagic) throw DecodeError("bad magic (not a skinstream subscriber stream)");
  if (version != kProtocolVersion)
    throw DecodeError("unsupported protocol version " + std::to_string(version) + " (this side speaks 1)");
  if (type < 1 || type > 5) throw DecodeError("unknown message type " + std::to_string(type));
  if (payload > max_payload)
    throw DecodeError("payload of " + std::to_string(payload) + " bytes exceeds the limit of " + std::to_string(max_payload));
  return {static_cast<MessageType>(type), payload};
}

Hello decode_hello(std::span<const unsigned char> payload) {
  return decode_payload("Hello", payload, [](ByteReader& r) {
    Hello hello{r.get<uint32_t>()};
    if (hello.wants & ~kWantAll) throw DecodeError("Hello: reserved wants bits set (" + std::to_string(hello.wants) + ")");
    return hello;
  });
}

Ack decode_ack(std::span<const unsigned char> payload) {
  return decode_payload("Ack", payload, [](ByteReader& r) { return Ack{r.get<uint32_t>()}; });
}

MeshInfo decode_mesh_info(std::span<const unsigned char> payload) {
  return decode_payload("MeshInfo", payload, [](ByteReader& r) {
    MeshInfo info;
    info.vertex_count = r.get<uint32_t>();
    const uint32_t face_count = r.get<uint32_t>();
    info.marker_count = r.get<uint32_t>();
    info.part_count = r.get<uint32_t>();
    info.source_rate_hz = r.get<float>();
    if (face_count > r.remaining() / 12 || info.vertex_count > r.remaining())
      throw std::out_of_range("vertex or face count exceeds the data left");
    info.faces.resize(face_count);
    for (auto& f : info.faces)
      for (uint32_t& v : f) {
        v = r.get<uint32_t>();
        if (v >= info.vertex_count) throw DecodeError("MeshInfo: face index " + std::to_string(v) + " out of range");
      }
    info.dominant_part.resize(info.vertex_count);
    for (uint8_t& p : info.dominant_part) p = r.get<uint8_t>();
    info.marker_triangles.resize(r.get_count(12));
    for (auto& t : info.marker_triangles)
      for (uint32_t& m : t) {
        m = r.get<uint32_t>();
        if (m >= info.marker_count) throw DecodeError("MeshInfo: marker triangle index " + std::to_string(m) + " out of range");
      }
    if (info.marker_count > r.remaining() / 2) throw std::out_of_range("marker count exceeds the data left");
    info.marker_names.resize(info.marker_count);
    for (std::string& name : info.marker_names) {
      const uint16_t n = r.get<uint16_t>();
      if (n > r.remaining()) throw std::out_of_range("marker name truncated");
      name.resize(n);
      for (char& c : name) c = r.get<char>();
    }
    return info;
  });
}

namespace {

// The fixed part of a Frame payload, checked against the sizes of what follows it; the reader is
// left at the first array.
FrameInfo read_frame_info(ByteReader& r) {
  FrameInfo info;
  info.frame_number = r.get<uint32_t>();
  info.flags = r.get<uint32_t>();
  info.source_time_ns = r.get<int64_t>();
  info.receive_time_ns = r.get<int64_t>();
  info.publish_time_ns = r.get<int64_t>();
  info.vertex_count = r.get<uint32_t>();
  info.marker_count = r.get<uint32_t>();
  info.markers_filled = r.get<uint16_t>();
  info.markers_relabelled = r.get<uint16_t>();
  info.pipeline_dropped = r.get<uint32_t>();
  info.subscriber_dropped = r.get<uint32_t>();
  if (info.flags & ~uint32_t{0xF}) throw DecodeError("Frame: reserved flag bits set (" + std::to_string(info.flags) + ")");
  const bool has_positions = !(info.flags & kFrameNoPositions);
  if (!has_positions && info.vertex_count != 0) throw DecodeError("Frame: vertex count with \"no positions\"");
  if (!has_positions && (info.flags & kFrameNormals)) throw DecodeError("Frame: normals without positions");
  if (!(info.flags & kFrameMarkers) && info.marker_count != 0) throw DecodeError("Frame: marker count without markers");
  // Sizes first, so a corrupt count is refused before anything is allocated for it.
  const size_t expected = frame_message_bytes(info.flags, info.vertex_count, info.marker_count) - kHeaderBytes - kFrameInfoBytes;
  if (expected != r.remaining())
    throw DecodeError("Frame: counts say " + std::to_string(expected) + " bytes of data, the payload holds " +
                      std::to_string(r.remaining()));
  return info;
}

}  // namespace

FrameInfo decode_frame_info(std::span<const unsigned char> payload) {
  return decode_payload("Frame", payload, [](ByteReader& r) {
    const FrameInfo info = read_frame_info(r);
    r.skip(r.remaining());
    return info;
  });
}

Frame decode_frame(std::span<const unsigned char> payload) {
  return decode_payload("Frame", payload, [](ByteReader& r) {
    Frame frame;
    frame.info = read_frame_info(r);
    const FrameInfo& info = frame.info;
    const bool has_positions = !(info.flags & kFrameNoPositions);
    const size_t v3 = 3 * size_t{info.vertex_count};
    const bool quantised = info.flags & kFrameQuantised;
    if (has_positions && !quantised) get_floats(r, frame.positions, v3);
    if (has_positions && quantised) {
      for (float& o : frame.origin) o = r.get<float>();
      for (float& s : frame.step) s = r.get<float>();
      frame.positions.resize(v3);
      for (size_t i = 0; i < v3; ++i) frame.positions[i] = frame.origin[i % 3] + r.get<uint16_t>() * frame.step[i % 3];
      for (size_t i = 0; i < padding_to_4(2 * v3); ++i) r.get<uint8_t>();
    }
    if ((info.flags & kFrameNormals) && !quantised) get_floats(r, frame.normals, v3);
    if ((info.flags & kFrameNormals) && quantised) {
      frame.normals.resize(v3);
      for (float& n : frame.normals) n = r.get<int16_t>() / 32767.0f;
      for (size_t i = 0; i < padding_to_4(2 * v3); ++i) r.get<uint8_t>();
    }
    if (info.flags & kFrameMarkers) {
      get_floats(r, frame.markers, 3 * size_t{info.marker_count});
      frame.marker_status.resize(info.marker_count);
      for (uint8_t& s : frame.marker_status) {
        s = r.get<uint8_t>();
        if (s > 4) throw DecodeError("Frame: marker status " + std::to_string(s) + " is not one of 0-4");
      }
      for (size_t i = 0; i < padding_to_4(info.marker_count); ++i) r.get<uint8_t>();
    }
    return frame;
  });
}

Status decode_status(std::span<const unsigned char> payload) {
  return decode_payload("Status", payload, [](ByteReader& r) {
    Status status;
    const uint32_t state = r.get<uint32_t>();
    if (state > 3) throw DecodeError("Status: unknown source state " + std::to_string(state));
    status.state = static_cast<SourceStateCode>(state);
    status.source_rate_hz = r.get<float>();
    status.frames_received = r.get<uint64_t>();
    status.frames_published = r.get<uint64_t>();
    status.detail.resize(r.get<uint16_t>());
    for (char& c : status.detail) c = r.get<char>();
    return status;
  });
}

void StreamDecoder::feed(std::span<const unsigned char> bytes) {
  const std::span<unsigned char> room = prepare(bytes.size());
  std::copy(bytes.begin(), bytes.end(), room.begin());
  commit(bytes.size());
}

std::span<unsigned char> StreamDecoder::prepare(size_t bytes) {
  if (consumed_ == filled_) consumed_ = filled_ = 0;  // everything was cut: start at the front for free
  if (buffer_.size() - filled_ < bytes) {
    // Move what is not cut yet (at most one partial message) to the front, then grow if need be.
    std::copy(buffer_.begin() + static_cast<std::ptrdiff_t>(consumed_), buffer_.begin() + static_cast<std::ptrdiff_t>(filled_),
              buffer_.begin());
    filled_ -= consumed_;
    consumed_ = 0;
    if (buffer_.size() - filled_ < bytes) buffer_.resize(filled_ + bytes);
  }
  return std::span(buffer_).subspan(filled_, bytes);
}

void StreamDecoder::commit(size_t bytes) { filled_ += std::min(bytes, buffer_.size() - filled_); }

std::optional<RawMessage> StreamDecoder::next() {
  const std::span<const unsigned char> pending(buffer_.data() + consumed_, filled_ - consumed_);
  if (pending.size() < kHeaderBytes) return std::nullopt;
  const MessageHeader header = decode_header(pending, max_payload_);
  if (pending.size() - kHeaderBytes < header.payload_bytes) return std::nullopt;
  consumed_ += kHeaderBytes + header.payload_bytes;
  return RawMessage{header.type, pending.subspan(kHeaderBytes, header.payload_bytes)};
}

}  // namespace skinstream::subscriber
