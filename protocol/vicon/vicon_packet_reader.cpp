#include "protocol/vicon/vicon_packet_reader.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "protocol/byte_reader.h"

namespace skinstream::vicon {
namespace {

// One object's payload: the reader, and the first value out of bounds (a name or a count over
// its limit), either of which stops the decoding. Reads chain with &&: each returns false once
// anything failed.
struct ObjectReader {
  explicit ObjectReader(Bytes payload) : bytes(payload) {}
  ByteReader bytes;
  std::string problem;

  template <typename T>
  bool read(T& out, const char* field) {
    return bytes.read(out, field);
  }
  bool read(bool& out, const char* field) {
    const uint8_t raw = bytes.get<uint8_t>(field);
    out = raw != 0;
    return bytes.ok();
  }
  template <typename T, size_t N>
  bool read(std::array<T, N>& out, const char* field) {
    return bytes.get_array(out.data(), N, field);
  }
  // A name (u32 length + bytes) of at most max_bytes.
  bool read_name(std::string& out, uint32_t max_bytes, const char* what) {
    uint32_t n = 0;
    if (!bytes.read(n, what)) return false;
    if (n > max_bytes)
      return fail(std::string(what) + " name of " + std::to_string(n) + " bytes exceeds the limit of " +
                  std::to_string(max_bytes));
    if (n > bytes.remaining())
      return fail(std::string(what) + " name of " + std::to_string(n) +
                  " bytes overruns the object at offset " + std::to_string(bytes.position()));
    const std::span<const unsigned char> name = bytes.take(n, what);
    out.assign(name.begin(), name.end());
    return true;
  }
  // A count of at most `limit` whose items (at least min_item_bytes each) must fit in what is left.
  bool read_count(uint32_t& out, size_t min_item_bytes, const char* what, uint32_t limit = UINT32_MAX) {
    if (!bytes.read(out, what)) return false;
    if (out > limit)
      return fail(std::string(what) + " count " + std::to_string(out) + " exceeds the limit of " + std::to_string(limit));
    if (min_item_bytes > 0 && out > bytes.remaining() / min_item_bytes)
      return fail(std::string(what) + " count " + std::to_string(out) + " exceeds the " +
                  std::to_string(bytes.remaining()) + " bytes left");
    return true;
  }
  bool fail(std::string reason) {
    if (problem.empty()) problem = std::move(reason);
    return false;
  }
};

bool finish(const ObjectReader& reader, bool ok, const char* object, std::string& out_error) {
  if (ok && reader.bytes.ok()) return true;
  out_error =
      std::string(object) + ": " + (reader.problem.empty() ? reader.bytes.error().message() : reader.problem);
  return false;
}

bool read_type_set(ObjectReader& c, std::vector<uint32_t>& out) {
  uint32_t n = 0;
  if (!c.read_count(n, 4, "type")) return false;
  out.resize(n);
  return c.bytes.get_array(out.data(), n, "type");
}

}  // namespace

bool split_objects(Bytes packet, std::vector<ObjectView>& out_objects, std::string& out_error,
                   const DescriptionLimits& limits) {
  out_objects.clear();
  if (packet.size() < kPacketHeaderBytes) {
    out_error = "packet of " + std::to_string(packet.size()) + " bytes is shorter than its 8-byte header";
    return false;
  }
  ByteReader r(packet);
  const uint32_t magic = r.get<uint32_t>("packet magic"), length = r.get<uint32_t>("packet length");
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
  uint32_t subjects = 0;
  while (r.remaining() > 0) {
    if (r.remaining() < kObjectHeaderBytes) {
      out_error = "truncated object header at offset " + std::to_string(r.position());
      return false;
    }
    ObjectView object;
    object.type = r.get<uint32_t>("object type");
    const uint32_t object_length = r.get<uint32_t>("object length");
    if (object_length > r.remaining()) {
      out_error = std::string(object_type_name(object.type)) + " object (type " +
                  std::to_string(object.type) + ") of " + std::to_string(object_length) +
                  " bytes overruns the packet at offset " + std::to_string(r.position() - kObjectHeaderBytes);
      return false;
    }
    object.payload = r.take(object_length, "object");
    if (object.type == object_type::SubjectInfo && ++subjects > limits.max_subjects) {
      out_error = "more than " + std::to_string(limits.max_subjects) + " SubjectInfo objects in one packet (the limit)";
      return false;
    }
    out_objects.push_back(object);
  }
  return true;
}

bool decode(Bytes payload, ObjectEnums& out, std::string& out_error) {
  ObjectReader c(payload);
  return finish(c, read_type_set(c, out.types), "ObjectEnums", out_error);
}

bool decode(Bytes payload, RequestFrame& out, std::string& out_error) {
  ObjectReader c(payload);
  return finish(c, c.read(out.streaming, "streaming"), "RequestFrame", out_error);
}

bool decode(Bytes payload, RequestNextFrame& out, std::string& out_error) {
  ObjectReader c(payload);
  return finish(c, c.read(out.count, "count"), "RequestNextFrame", out_error);
}

bool decode(Bytes payload, Ping& out, std::string& out_error) {
  ObjectReader c(payload);
  return finish(c, c.read(out.id, "id"), "Ping", out_error);
}

bool decode(Bytes payload, StartMulticastSender& out, std::string& out_error) {
  ObjectReader c(payload);
  const bool ok = c.read(out.multicast_address, "multicast address") &&
                  c.read(out.source_address, "source address") && c.read(out.port, "port");
  return finish(c, ok, "StartMulticastSender", out_error);
}

bool decode(Bytes payload, Contents& out, std::string& out_error) {
  ObjectReader c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, 8, "table");
  if (ok) {
    out.table.resize(n);
    for (auto& [type, value] : out.table)
      if (!(ok = c.read(type, "type") && c.read(value, "value"))) break;
  }
  ok = ok && read_type_set(c, out.unchanged);
  return finish(c, ok, "Contents", out_error);
}

bool decode(Bytes payload, Filter& out, std::string& out_error) {
  ObjectReader c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, 8, "filter");
  if (ok) {
    out.filters.resize(n);
    for (auto& [type, ids] : out.filters)
      if (!(ok = c.read(type, "type") && read_type_set(c, ids))) break;
  }
  return finish(c, ok, "Filter", out_error);
}

bool decode(Bytes payload, StreamInfo& out, std::string& out_error) {
  ObjectReader c(payload);
  bool ok = c.read(out.frame_period_ticks, "frame period ticks");
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
  ObjectReader c(payload);
  uint32_t n = 0;
  const uint32_t max_items = limits.max_markers_per_subject, max_name = limits.max_name_bytes;
  bool ok = c.read(out.subject_id, "subject id") && c.read_name(out.name, max_name, "subject") &&
            c.read_count(n, 4 + 4 + 24 + 4, "segment", max_items);
  if (ok) {
    out.segments.resize(n);
    for (SubjectSegment& s : out.segments)
      if (!(ok = c.read(s.parent_id, "parent id") && c.read(s.segment_id, "segment id") &&
                 c.read(s.bounds, "bounds") && c.read_name(s.name, max_name, "segment")))
        break;
  }
  ok = ok && c.read_count(n, 4 + 4, "marker", max_items);
  if (ok) {
    out.markers.resize(n);
    for (SubjectMarker& m : out.markers)
      if (!(ok = c.read(m.marker_id, "marker id") && c.read_name(m.name, max_name, "marker"))) break;
  }
  ok = ok && c.read_count(n, 4 + 4, "attachment", max_items);
  if (ok) {
    out.attachments.resize(n);
    for (SubjectAttachment& a : out.attachments)
      if (!(ok = c.read(a.marker_id, "marker id") && c.read(a.segment_id, "segment id"))) break;
  }
  return finish(c, ok, "SubjectInfo", out_error);
}

bool decode(Bytes payload, FrameInfo& out, std::string& out_error) {
  ObjectReader c(payload);
  return finish(c, c.read(out.frame_id, "frame id"), "FrameInfo", out_error);
}

bool decode(Bytes payload, Timecode& out, std::string& out_error) {
  ObjectReader c(payload);
  const bool ok =
      c.read(out.hours, "hours") && c.read(out.minutes, "minutes") && c.read(out.seconds, "seconds") &&
      c.read(out.frames, "frames") && c.read(out.subframes, "subframes") &&
      c.read(out.subframes_per_frame, "subframes per frame") && c.read(out.standard, "standard") &&
      c.read(out.user_bits, "user bits") && c.read(out.field_flag, "field flag");
  return finish(c, ok, "Timecode", out_error);
}

bool decode(Bytes payload, std::vector<LabeledRecon>& out, std::string& out_error) {
  ObjectReader c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, kLabeledReconBytes, "recon");
  out.clear();
  for (uint32_t i = 0; ok && i < n; ++i) {
    LabeledRecon& r = out.emplace_back();
    ok = c.read(r.subject_id, "subject id") && c.read(r.marker_id, "marker id") &&
         c.read(r.radius, "radius") && c.read(r.position, "position") && c.read(r.covariance, "covariance") &&
         c.read(r.trajectory_id, "trajectory id");
  }
  return finish(c, ok, "LabeledRecons", out_error);
}

bool decode(Bytes payload, std::vector<UnlabeledRecon>& out, std::string& out_error) {
  ObjectReader c(payload);
  uint32_t n = 0;
  bool ok = c.read_count(n, kUnlabeledReconBytes, "recon");
  out.clear();
  for (uint32_t i = 0; ok && i < n; ++i) {
    UnlabeledRecon& r = out.emplace_back();
    ok = c.read(r.radius, "radius") && c.read(r.position, "position") && c.read(r.covariance, "covariance") &&
         c.read(r.trajectory_id, "trajectory id");
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
