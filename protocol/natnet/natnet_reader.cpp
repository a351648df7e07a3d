#include "protocol/natnet/natnet_reader.h"

#include <algorithm>
#include <cstring>
#include <string_view>

#include "protocol/byte_reader.h"

namespace skinstream::natnet {
namespace {

// One message's reader: the bytes, and the first value out of bounds (a count, a section's byte
// count, a name without its NUL), which stops the reader as a read past the end does. Once
// stopped, every read gives zero, so loops over counts end and nothing more is judged.
struct MessageReader {
  explicit MessageReader(Bytes payload) : bytes(payload) {}
  ByteReader bytes;
  std::string problem;

  bool ok() const { return bytes.ok(); }
  // The first problem; the reader stops (nothing is kept if it had stopped already).
  void fail(const char* field, std::string reason) {
    if (!ok()) return;
    problem = std::move(reason);
    bytes.fail(field, 0);
  }
  std::string error() const { return problem.empty() ? bytes.error().message() : problem; }

  template <typename T>
  T get(const char* what) {
    return bytes.get<T>(what);
  }
  Point point(const char* what) {
    Point p{};
    bytes.get_array(p.data(), p.size(), what);
    return p;
  }
  // A count of items of at least `min_item_bytes` each, which must fit in what is left.
  uint32_t count(size_t min_item_bytes, const char* what) {
    const int32_t n = bytes.get<int32_t>(what);
    if (n < 0) {
      fail(what, std::string(what) + " count " + std::to_string(n) + " is negative");
      return 0;
    }
    if (static_cast<size_t>(n) > bytes.remaining() / min_item_bytes) {
      fail(what, std::string(what) + " count " + std::to_string(n) + " exceeds the " +
                     std::to_string(bytes.remaining()) + " bytes left");
      return 0;
    }
    return static_cast<uint32_t>(n);
  }
  // A NUL-terminated string in place; empty once stopped.
  std::string_view cstring(const char* what) {
    if (!ok()) return {};
    const auto* start = reinterpret_cast<const char*>(bytes.here());
    const size_t length = strnlen(start, bytes.remaining());
    if (length == bytes.remaining()) {
      fail(what, std::string(what) + " has no terminating NUL");
      return {};
    }
    bytes.skip(length + 1, what);
    return {start, length};
  }
  void skip(size_t n, const char* what) { bytes.skip(n, what); }
  size_t remaining() const { return bytes.remaining(); }
  size_t position() const { return bytes.position(); }
};

// A section's 4.1 byte count, checked once the section has been read.
class Section {
 public:
  Section(MessageReader& c, Version version, const char* what) : c_(c), what_(what) {
    if (version.has_section_bytes()) {
      declared_ = c.get<int32_t>(what);
      if (declared_ < 0 || static_cast<size_t>(declared_) > c.remaining()) {
        c.fail(what, std::string(what) + " says " + std::to_string(declared_) + " bytes with " +
                         std::to_string(c.remaining()) + " left");
        declared_ = 0;
      }
    }
    start_ = c.position();
  }
  void check() const {
    if (c_.ok() && declared_ >= 0 && c_.position() - start_ != static_cast<size_t>(declared_))
      c_.fail(what_, std::string(what_) + " says " + std::to_string(declared_) + " bytes but holds " +
                         std::to_string(c_.position() - start_));
  }
  int32_t declared() const { return declared_; }

 private:
  MessageReader& c_;
  const char* what_;
  int32_t declared_ = -1;
  size_t start_ = 0;
};

constexpr size_t kRigidBodyBytes = 4 + 12 + 16 + 4 + 2;  // 3.0+: id, position, orientation, error, params
constexpr size_t kLabelledMarkerBytes = 4 + 12 + 4 + 2 + 4;

void skip_channels(MessageReader& c, const char* what) {  // force plates and devices
  c.skip(4, what);                                        // id
  const uint32_t channels = c.count(4, what);
  for (uint32_t k = 0; k < channels && c.ok(); ++k) c.skip(4 * static_cast<size_t>(c.count(4, what)), what);
}

void skip_rigid_body_description(MessageReader& c, Version version) {
  c.cstring("rigid body description name");
  c.skip(4 + 4 + 12, "rigid body description");  // id, parent id, offset
  const uint32_t markers = c.count(16, "rigid body description markers");
  c.skip(16 * static_cast<size_t>(markers), "rigid body description markers");  // offsets, active labels
  if (version.major >= 4)
    for (uint32_t m = 0; m < markers && c.ok(); ++m) c.cstring("rigid body marker name");
}

bool refuse_version(Version version, std::string& out_error) {
  if (version.supported()) return false;
  out_error = "NatNet " + std::to_string(version.major) + "." + std::to_string(version.minor) +
              " is not supported (3.0 or later)";
  return true;
}

bool finish(const MessageReader& c, std::string& out_error) {
  if (c.ok()) return true;
  out_error = c.error();
  return false;
}

}  // namespace

TimecodeFields split_timecode(uint32_t timecode) {
  return {static_cast<int>(timecode >> 24 & 0xFF), static_cast<int>(timecode >> 16 & 0xFF),
          static_cast<int>(timecode >> 8 & 0xFF), static_cast<int>(timecode & 0xFF)};
}

int64_t capture_latency_ns(const FrameOfData& frame, uint64_t clock_ticks_per_second) {
  if (clock_ticks_per_second == 0 || frame.stamp_mid_exposure == 0 ||
      frame.stamp_transmit < frame.stamp_mid_exposure)
    return -1;
  const uint64_t ticks = frame.stamp_transmit - frame.stamp_mid_exposure;
  if (ticks > clock_ticks_per_second) return -1;
  return static_cast<int64_t>(static_cast<long double>(ticks) * 1e9L /
                              static_cast<long double>(clock_ticks_per_second));
}

uint32_t join_timecode(const TimecodeFields& f) {
  return static_cast<uint32_t>(f.hours & 0xFF) << 24 | static_cast<uint32_t>(f.minutes & 0xFF) << 16 |
         static_cast<uint32_t>(f.seconds & 0xFF) << 8 | static_cast<uint32_t>(f.frames & 0xFF);
}

bool read_message(Bytes datagram, uint16_t& out_id, Bytes& out_payload, std::string& out_error) {
  if (datagram.size() < kHeaderBytes) {
    out_error = "datagram of " + std::to_string(datagram.size()) + " bytes is shorter than its 4-byte header";
    return false;
  }
  ByteReader r(datagram);
  out_id = r.get<uint16_t>("message id");
  const uint16_t bytes = r.get<uint16_t>("message bytes");
  if (bytes > datagram.size() - kHeaderBytes) {
    out_error = "message " + std::to_string(out_id) + " says " + std::to_string(bytes) + " bytes but " +
                std::to_string(datagram.size() - kHeaderBytes) + " follow";
    return false;
  }
  out_payload = datagram.subspan(kHeaderBytes, bytes);
  return true;
}

bool decode_server_info(Bytes payload, ServerInfo& out, std::string& out_error) {
  constexpr size_t kNameBytes = 256;
  if (payload.size() < kNameBytes + 8) {
    out_error = "server info of " + std::to_string(payload.size()) + " bytes (at least 264)";
    return false;
  }
  MessageReader c(payload);
  const auto* name = reinterpret_cast<const char*>(payload.data());
  const size_t length = strnlen(name, kNameBytes);
  if (length == kNameBytes) {
    out_error = "server info name has no terminating NUL";
    return false;
  }
  out.application_name.assign(name, length);
  c.skip(kNameBytes, "server info name");
  c.bytes.get_array(out.application_version.data(), out.application_version.size(), "application version");
  c.bytes.get_array(out.natnet_version.data(), out.natnet_version.size(), "NatNet version");
  if (c.remaining() > 0) {  // NatNet 3.0+: clock, data port, multicast group (15 bytes)
    out.clock_ticks_per_second = c.get<uint64_t>("clock frequency");
    out.data_port = c.get<uint16_t>("data port");
    out.multicast = c.get<uint8_t>("multicast flag") != 0;
    c.bytes.get_array(out.multicast_group.data(), out.multicast_group.size(), "multicast group");
  }
  return finish(c, out_error);
}

bool decode_model_definitions(Bytes payload, Version version, ModelDefinitions& out, std::string& out_error) {
  out.marker_sets.clear();
  out.skipped_descriptions = 0;
  if (refuse_version(version, out_error)) return false;
  MessageReader c(payload);
  const uint32_t count = c.count(4, "model definitions");
  for (uint32_t i = 0; i < count && c.ok(); ++i) {
    const int32_t type = c.get<int32_t>("description type");
    Section section(c, version, "description");
    if (!c.ok()) break;
    switch (type) {
      case 0: {
        MarkerSetDescription& set = out.marker_sets.emplace_back();
        set.name = c.cstring("marker set name");
        const uint32_t markers = c.count(1, "marker set names");
        set.markers.resize(markers);
        for (std::string& name : set.markers) name = c.cstring("marker name");
        break;
      }
      case 1:
        skip_rigid_body_description(c, version);
        ++out.skipped_descriptions;
        break;
      case 2: {
        c.cstring("skeleton name");
        c.skip(4, "skeleton id");
        const uint32_t bones = c.count(1, "skeleton bones");
        for (uint32_t b = 0; b < bones && c.ok(); ++b) skip_rigid_body_description(c, version);
        ++out.skipped_descriptions;
        break;
      }
      default:
        if (section.declared() < 0) {
          c.fail("description",
                 "description type " + std::to_string(type) + " cannot be skipped before NatNet 4.1");
          break;
        }
        c.skip(static_cast<size_t>(section.declared()), "description");
        ++out.skipped_descriptions;
        break;
    }
    section.check();
  }
  return finish(c, out_error);
}

bool decode_frame(Bytes payload, Version version, FrameOfData& out, std::string& out_error) {
  if (refuse_version(version, out_error)) return false;
  MessageReader c(payload);
  out.frame_number = c.get<int32_t>("frame number");

  out.marker_set_count = c.count(5, "marker sets");
  {
    Section section(c, version, "marker sets");
    if (out.marker_sets.size() < out.marker_set_count) out.marker_sets.resize(out.marker_set_count);
    for (size_t s = 0; s < out.marker_set_count && c.ok(); ++s) {
      MarkerSetData& set = out.marker_sets[s];
      set.name = c.cstring("marker set name");
      set.positions.resize(c.count(12, "marker set markers"));
      for (Point& p : set.positions) p = c.point("marker set markers");
    }
    section.check();
  }
  {
    const uint32_t n = c.count(12, "other markers");
    Section section(c, version, "other markers");
    out.other_markers.resize(n);
    for (Point& p : out.other_markers) p = c.point("other markers");
    section.check();
  }
  {
    out.rigid_bodies = c.count(kRigidBodyBytes, "rigid bodies");
    Section section(c, version, "rigid bodies");
    c.skip(kRigidBodyBytes * out.rigid_bodies, "rigid bodies");
    section.check();
  }
  {
    out.skeletons = c.count(8, "skeletons");
    Section section(c, version, "skeletons");
    for (uint32_t s = 0; s < out.skeletons && c.ok(); ++s) {
      c.skip(4, "skeleton id");
      c.skip(kRigidBodyBytes * c.count(kRigidBodyBytes, "skeleton bones"), "skeleton bones");
    }
    section.check();
  }
  if (version.has_section_bytes()) {  // assets (Motive 3.1+), skipped whole
    out.assets = c.count(1, "assets");
    Section section(c, version, "assets");
    c.skip(static_cast<size_t>(std::max(section.declared(), 0)), "assets");
  }
  {
    const uint32_t n = c.count(kLabelledMarkerBytes, "labelled markers");
    Section section(c, version, "labelled markers");
    out.labelled_markers.resize(n);
    for (LabelledMarker& m : out.labelled_markers) {
      m.id = c.get<uint32_t>("labelled marker id");
      m.position = c.point("labelled marker position");
      m.size = c.get<float>("labelled marker size");
      m.params = c.get<int16_t>("labelled marker params");
      m.residual = c.get<float>("labelled marker residual");
    }
    section.check();
  }
  for (uint32_t* counted : {&out.force_plates, &out.devices}) {
    const char* what = counted == &out.force_plates ? "force plates" : "devices";
    *counted = c.count(8, what);
    Section section(c, version, what);
    for (uint32_t i = 0; i < *counted && c.ok(); ++i) skip_channels(c, what);
    section.check();
  }
  out.timecode = c.get<uint32_t>("timecode");
  out.timecode_subframe = c.get<uint32_t>("timecode subframe");
  out.timestamp_s = c.get<double>("timestamp");
  out.stamp_mid_exposure = c.get<uint64_t>("mid-exposure stamp");
  out.stamp_data_received = c.get<uint64_t>("data received stamp");
  out.stamp_transmit = c.get<uint64_t>("transmit stamp");
  if (version.has_precise_timestamp()) {
    out.precise_seconds = c.get<uint32_t>("precise timestamp");
    out.precise_fraction = c.get<uint32_t>("precise timestamp fraction");
  }
  out.params = c.get<int16_t>("frame params");
  if (c.remaining() >= 4) c.skip(4, "end of data");
  if (c.ok() && c.remaining() > 0)
    c.fail("end of data", "frame has " + std::to_string(c.remaining()) + " bytes after its end of data");
  return finish(c, out_error);
}

bool decode_message(Bytes datagram, Version version, Message& out, std::string& out_error) {
  Bytes payload;
  if (!read_message(datagram, out.id, payload, out_error)) return false;
  switch (out.id) {
    case message::ServerInfo:
      return decode_server_info(payload, out.server_info, out_error);
    case message::ModelDef:
      return decode_model_definitions(payload, version, out.model_definitions, out_error);
    case message::FrameOfData:
      return decode_frame(payload, version, out.frame, out_error);
    case message::Request:
    case message::Response:
    case message::MessageString: {
      const auto* text = reinterpret_cast<const char*>(payload.data());
      out.text.assign(text, strnlen(text, payload.size()));
      return true;
    }
    case message::Connect:
    case message::RequestModelDef:
    case message::RequestFrameOfData:
    case message::Disconnect:
    case message::KeepAlive:
      return true;
    default:
      out_error = "unknown NatNet message id " + std::to_string(out.id);
      return false;
  }
}

}  // namespace skinstream::natnet
