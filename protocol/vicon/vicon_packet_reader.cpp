#include "protocol/vicon/vicon_packet_reader.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace skinstream::vicon {
namespace {

// A bounds-checked little-endian cursor over one payload. The first failure sticks.
class Cursor {
 public:
  explicit Cursor(Bytes bytes) : bytes_(bytes) {}

  template <typename T>
  bool read(T& out) {
    static_assert(std::is_arithmetic_v<T>);
    if (sizeof(T) > remaining()) return fail("truncated: needs " + std::to_string(sizeof(T)) + " bytes at offset " +
                                             std::to_string(pos_) + " of " + std::to_string(bytes_.size()));
    std::memcpy(&out, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool read(bool& out) {
    uint8_t raw = 0;
    if (!read(raw)) return false;
    out = raw != 0;
    return true;
  }
  template <typename T, size_t N>
  bool read(std::array<T, N>& out) {
    for (T& v : out)
      if (!read(v)) return false;
    return true;
  }
  // A name (u32 length + bytes) of at most max_bytes.
  bool read_name(std::string& out, uint32_t max_bytes, const char* what) {
    uint32_t n = 0;
    if (!read(n)) return false;
    if (n > max_bytes)
      return fail(std::string(what) + " name of " + std::to_string(n) + " bytes exceeds the limit of " +
                  std::to_string(max_bytes));
    if (n > remaining())
      return fail(std::string(what) + " name of " + std::to_string(n) + " bytes overruns the object at offset " +
                  std::to_string(pos_));
    out.assign(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return true;
  }
  // A count of at most `limit` whose items (at least min_item_bytes each) must fit in what is left.
  bool read_count(uint32_t& out, size_t min_item_bytes, const char* what, uint32_t limit = UINT32_MAX) {
    if (!read(out)) return false;
    if (out > limit)
      return fail(std::string(what) + " count " + std::to_string(out) + " exceeds the limit of " + std::to_string(limit));
    if (min_item_bytes > 0 && out > remaining() / min_item_bytes)
      return fail(std::string(what) + " count " + std::to_string(out) + " exceeds the " + std::to_string(remaining()) +
                  " bytes left");
    return true;
  }
  bool fail(std::string reason) {
    if (error_.empty()) error_ = std::move(reason);
    return false;
  }
  size_t remaining() const { return bytes_.size() - pos_; }
  const std::string& error() const { return error_; }

 private:
  Bytes bytes_;
  size_t pos_ = 0;
  std::string error_;
};

bool finish(Cursor& cursor, bool ok, const char* object, std::string& out_error) {
  if (ok) return true;
  out_error = std::string(object) + ": " + cursor.error();
  return false;
}

bool read_type_set(Cursor& c, std::vector<uint32_t>& out) {
  uint32_t n = 0;
  if (!c.read_count(n, 4, "type")) return false;
  out.resize(n);
  for (uint32_t& t : out)
    if (!c.read(t)) return false;
  return true;
}

}  // namespace

bool split_objects(Bytes packet, std::vector<ObjectView>& out_objects, std::string& out_error,
                   const DescriptionLimits& limits) {
  out_objects.clear();
  if (packet.size() < kPacketHeaderBytes) {
    out_error = "packet of " + std::to_string(packet.size()) + " bytes is shorter than its 8-byte header";
    return false;
  }
  uint32_t magic = 0, length = 0;
  std::memcpy(&magic, packet.data(), 4);
  std::memcpy(&length, packet.data() + 4, 4);
  if (magic != kPacketMagic) {
    char hex[16];
    std::snprintf(hex, sizeof(hex), "0x%08X", magic);
    out_error = std::string("bad packet magic ") + hex + " (expected 0x1A2B0001)";
    return false;
  }
  if (length > kMaxPacketLength) {
    out_error = "packet length " + std::to_string(length) + " exceeds the 16 MiB limit";
    return false;
  }
  if (length != packet.size() - kPacketHeaderBytes) {
    out_error = "packet length " + std::to_string(length) + " but " + std::to_string(packet.size() - kPacketHeaderBytes) +
                " bytes follow the header";
    return false;
  }
  size_t pos = kPacketHeaderBytes;
  uint32_t subjects = 0;
  while (pos < packet.size()) {
    if (packet.size() - pos < kObjectHeaderBytes) {
      out_error = "truncated object header at offset " + std::to_string(pos);
      return false;
    }
    ObjectView object;
    uint32_t object_length = 0;
    std::memcpy(&object.type, packet.data() + pos, 4);
    std::memcpy(&object_length, packet.data() + pos + 4, 4);
    pos += kObjectHeaderBytes;
    if (object_length > packet.size() - pos) {
      out_error = std::string(object_type_name(object.type)) + " object (type " + std::to_string(object.type) +
                  ") of " + std::to_string(object_length) + " bytes overruns the packet at offset " +
                  std::to_string(pos - kObjectHeaderBytes);
      return false;
    }
    object.payload = packet.subspan(pos, object_length);
    pos += object_length;
    if (object.type == object_type::SubjectInfo && ++subjects > limits.max_subjects) {
      out_error = "more than " + std::to_string(limits.max_subjects) + " SubjectInfo objects in one packet (the limit)";
      return false;
    }
    out_objects.push_back(object);
  }
  return true;
}

bool decode(Bytes payload, ObjectEnums& out, std::string& out_error) {
  Cursor c(payload);
  return finish(c, read_type_set(c, out.types), "ObjectEnums", out_error);
}

bool decode(Bytes payload, RequestFrame& out, std::string& out_error) {
  Cursor c(payload);
  return finish(c, c.read(out.streaming), "RequestFrame", out_error);
}

bool decode(Bytes payload, RequestNextFrame& out, std::string& out_error) {
  Cursor c(payload);
  return finish(c, c.read(out.count), "RequestNextFrame", out_error);
}

bool decode(Bytes payload, Ping& out, std::string& out_error) {
  Cursor c(payload);
  return finish(c, c.read(out.id), "Ping", out_error);
}

bool decode(Bytes payload, StartMulticastSender& out, std::string& out_error) {
  Cursor c(payload);
  const bool ok = c.read(out.multicast_address) && c.read(out.source_address) && c.read(out.port);
  return finish(c, ok, "StartMulticastSender", out_error);
}

bool decode(Bytes payload, Contents& out, std::string& out_error) {
  Cursor c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, 8, "table");
  if (ok) {
    out.table.resize(n);
    for (auto& [type, value] : out.table)
      if (!(ok = c.read(type) && c.read(value))) break;
  }
  ok = ok && read_type_set(c, out.unchanged);
  return finish(c, ok, "Contents", out_error);
}

bool decode(Bytes payload, Filter& out, std::string& out_error) {
  Cursor c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, 8, "filter");
  if (ok) {
    out.filters.resize(n);
    for (auto& [type, ids] : out.filters)
      if (!(ok = c.read(type) && read_type_set(c, ids))) break;
  }
  return finish(c, ok, "Filter", out_error);
}

bool decode(Bytes payload, StreamInfo& out, std::string& out_error) {
  Cursor c(payload);
  bool ok = c.read(out.frame_period_ticks);
  if (ok && (out.frame_period_ticks < kMinFramePeriodTicks || out.frame_period_ticks > kMaxFramePeriodTicks)) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.6g", rate_from_period(out.frame_period_ticks));
    ok = c.fail("frame period of " + std::to_string(out.frame_period_ticks) + " ticks (" +
                (out.frame_period_ticks > 0 ? std::string(rate) + " Hz" : std::string("no rate")) +
                ") is outside 1 Hz to 10 kHz");
  }
  return finish(c, ok, "StreamInfo", out_error);
}

bool decode(Bytes payload, SubjectInfo& out, std::string& out_error, const DescriptionLimits& limits) {
  Cursor c(payload);
  uint32_t n = 0;
  const uint32_t max_items = limits.max_markers_per_subject, max_name = limits.max_name_bytes;
  bool ok = c.read(out.subject_id) && c.read_name(out.name, max_name, "subject") &&
            c.read_count(n, 4 + 4 + 24 + 4, "segment", max_items);
  if (ok) {
    out.segments.resize(n);
    for (SubjectSegment& s : out.segments)
      if (!(ok = c.read(s.parent_id) && c.read(s.segment_id) && c.read(s.bounds) && c.read_name(s.name, max_name, "segment"))) break;
  }
  ok = ok && c.read_count(n, 4 + 4, "marker", max_items);
  if (ok) {
    out.markers.resize(n);
    for (SubjectMarker& m : out.markers)
      if (!(ok = c.read(m.marker_id) && c.read_name(m.name, max_name, "marker"))) break;
  }
  ok = ok && c.read_count(n, 4 + 4, "attachment", max_items);
  if (ok) {
    out.attachments.resize(n);
    for (SubjectAttachment& a : out.attachments)
      if (!(ok = c.read(a.marker_id) && c.read(a.segment_id))) break;
  }
  return finish(c, ok, "SubjectInfo", out_error);
}

bool decode(Bytes payload, FrameInfo& out, std::string& out_error) {
  Cursor c(payload);
  return finish(c, c.read(out.frame_id), "FrameInfo", out_error);
}

bool decode(Bytes payload, Timecode& out, std::string& out_error) {
  Cursor c(payload);
  const bool ok = c.read(out.hours) && c.read(out.minutes) && c.read(out.seconds) && c.read(out.frames) &&
                  c.read(out.subframes) && c.read(out.subframes_per_frame) && c.read(out.standard) &&
                  c.read(out.user_bits) && c.read(out.field_flag);
  return finish(c, ok, "Timecode", out_error);
}

bool decode(Bytes payload, std::vector<LabeledRecon>& out, std::string& out_error) {
  Cursor c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, kLabeledReconBytes, "recon");
  out.clear();
  for (uint32_t i = 0; ok && i < n; ++i) {
    LabeledRecon& r = out.emplace_back();
    ok = c.read(r.subject_id) && c.read(r.marker_id) && c.read(r.radius) && c.read(r.position) &&
         c.read(r.covariance) && c.read(r.trajectory_id);
  }
  return finish(c, ok, "LabeledRecons", out_error);
}

bool decode(Bytes payload, std::vector<UnlabeledRecon>& out, std::string& out_error) {
  Cursor c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, kUnlabeledReconBytes, "recon");
  out.clear();
  for (uint32_t i = 0; ok && i < n; ++i) {
    UnlabeledRecon& r = out.emplace_back();
    ok = c.read(r.radius) && c.read(r.position) && c.read(r.covariance) && c.read(r.trajectory_id);
  }
  return finish(c, ok, "UnlabeledRecons", out_error);
}

bool DecodedPacket::has(uint32_t type) const {
  return std::find(object_types.begin(), object_types.end(), type) != object_types.end();
}

bool decode_packet(Bytes packet, DecodedPacket& out, std::string& out_error, const DescriptionLimits& limits) {
  out = DecodedPacket{};
  std::vector<ObjectView> objects;
  if (!split_objects(packet, objects, out_error, limits)) return false;
  for (const ObjectView& object : objects) {
    out.object_types.push_back(object.type);
    bool ok = true;
    switch (object.type) {
      case object_type::ObjectEnums: ok = decode(object.payload, out.object_enums, out_error); break;
      case object_type::RequestFrame: ok = decode(object.payload, out.request_frame, out_error); break;
      case object_type::RequestNextFrame: ok = decode(object.payload, out.request_next_frame, out_error); break;
      case object_type::Ping: ok = decode(object.payload, out.ping, out_error); break;
      case object_type::StartMulticastSender: ok = decode(object.payload, out.start_multicast, out_error); break;
      case object_type::StopMulticastSender: break;
      case object_type::Contents: ok = decode(object.payload, out.contents, out_error); break;
      case object_type::Filter: ok = decode(object.payload, out.filter, out_error); break;
      case object_type::StreamInfo: ok = decode(object.payload, out.stream_info, out_error); break;
      case object_type::SubjectInfo: ok = decode(object.payload, out.subjects.emplace_back(), out_error, limits); break;
      case object_type::FrameInfo: ok = decode(object.payload, out.frame_info, out_error); break;
      case object_type::Timecode: ok = decode(object.payload, out.timecode, out_error); break;
      case object_type::LabeledRecons: ok = decode(object.payload, out.labeled, out_error); break;
      case object_type::UnlabeledRecons: ok = decode(object.payload, out.unlabeled, out_error); break;
      default: out.unknown_types.push_back(object.type); break;
    }
    if (!ok) return false;
  }
  return true;
}

}  // namespace skinstream::vicon
