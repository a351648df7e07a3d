#include "protocol/natnet/natnet_writer.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace skinstream::natnet {
namespace {

class Out {
 public:
  explicit Out(ByteVector& bytes, uint16_t message_id) : bytes_(bytes) {
    bytes_.clear();
    put<uint16_t>(message_id);
    put<uint16_t>(0);  // byte count, filled in by finish()
  }
  template <typename T>
  void put(T value) {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }
  void put_point(const Point& p) {
    for (float v : p) put<float>(v);
  }
  void put_cstring(std::string_view s) {
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  void put_fixed(std::string_view s, size_t size) {  // NUL-padded, always NUL-terminated
    const size_t n = std::min(s.size(), size - 1);
    bytes_.insert(bytes_.end(), s.begin(), s.begin() + static_cast<long>(n));
    bytes_.insert(bytes_.end(), size - n, 0);
  }
  // A 4.1 section byte count, filled in by end_section(); nothing before 4.1.
  size_t begin_section(Version version) {
    if (!version.has_section_bytes()) return 0;
    put<int32_t>(0);
    return bytes_.size();
  }
  void end_section(Version version, size_t start) {
    if (!version.has_section_bytes()) return;
    const auto bytes = static_cast<int32_t>(bytes_.size() - start);
    std::memcpy(bytes_.data() + start - 4, &bytes, 4);
  }
  void finish() {
    const size_t payload = bytes_.size() - kHeaderBytes;
    if (payload > 0xFFFF)
      throw std::length_error("NatNet message of " + std::to_string(payload) + " bytes exceeds 65535");
    const auto count = static_cast<uint16_t>(payload);
    std::memcpy(bytes_.data() + 2, &count, 2);
  }

 private:
  ByteVector& bytes_;
};

}  // namespace

ByteVector encode_empty(uint16_t message_id) {
  ByteVector bytes;
  Out(bytes, message_id).finish();
  return bytes;
}

ByteVector encode_connect(std::string_view client_name, Version wanted) {
  ByteVector bytes;
  Out out(bytes, message::Connect);
  out.put_fixed(client_name, 256);
  for (int i = 0; i < 4; ++i) out.put<uint8_t>(0);  // the client's own version
  out.put<uint8_t>(static_cast<uint8_t>(wanted.major));
  out.put<uint8_t>(static_cast<uint8_t>(wanted.minor));
  out.put<uint8_t>(0);
  out.put<uint8_t>(0);
  out.finish();
  return bytes;
}

ByteVector encode_server_info(const ServerInfo& info) {
  ByteVector bytes;
  Out out(bytes, message::ServerInfo);
  out.put_fixed(info.application_name, 256);
  for (uint8_t v : info.application_version) out.put<uint8_t>(v);
  for (uint8_t v : info.natnet_version) out.put<uint8_t>(v);
  out.put<uint64_t>(info.clock_ticks_per_second);
  out.put<uint16_t>(info.data_port);
  out.put<uint8_t>(info.multicast ? 1 : 0);
  for (uint8_t v : info.multicast_group) out.put<uint8_t>(v);
  out.finish();
  return bytes;
}

ByteVector encode_model_definitions(const ModelDefinitions& definitions, Version version) {
  ByteVector bytes;
  Out out(bytes, message::ModelDef);
  out.put<int32_t>(static_cast<int32_t>(definitions.marker_sets.size()));
  for (const MarkerSetDescription& set : definitions.marker_sets) {
    out.put<int32_t>(0);  // marker set
    const size_t section = out.begin_section(version);
    out.put_cstring(set.name);
    out.put<int32_t>(static_cast<int32_t>(set.markers.size()));
    for (const std::string& name : set.markers) out.put_cstring(name);
    out.end_section(version, section);
  }
  out.finish();
  return bytes;
}

ByteVector encode_text(uint16_t message_id, std::string_view text) {
  ByteVector bytes;
  Out out(bytes, message_id);
  out.put_cstring(text);
  out.finish();
  return bytes;
}

void encode_frame(const FrameOfData& frame, Version version, ByteVector& bytes) {
  Out out(bytes, message::FrameOfData);
  out.put<int32_t>(frame.frame_number);

  out.put<int32_t>(static_cast<int32_t>(frame.marker_set_count));
  size_t section = out.begin_section(version);
  for (size_t s = 0; s < frame.marker_set_count; ++s) {
    out.put_cstring(frame.marker_sets[s].name);
    out.put<int32_t>(static_cast<int32_t>(frame.marker_sets[s].positions.size()));
    for (const Point& p : frame.marker_sets[s].positions) out.put_point(p);
  }
  out.end_section(version, section);

  out.put<int32_t>(static_cast<int32_t>(frame.other_markers.size()));
  section = out.begin_section(version);
  for (const Point& p : frame.other_markers) out.put_point(p);
  out.end_section(version, section);

  // No rigid bodies, skeletons or (4.1) assets: a replay of markers has none.
  const int empty_sections = version.has_section_bytes() ? 3 : 2;
  for (int i = 0; i < empty_sections; ++i) {
    out.put<int32_t>(0);
    out.end_section(version, out.begin_section(version));
  }

  out.put<int32_t>(static_cast<int32_t>(frame.labelled_markers.size()));
  section = out.begin_section(version);
  for (const LabelledMarker& m : frame.labelled_markers) {
    out.put<uint32_t>(m.id);
    out.put_point(m.position);
    out.put<float>(m.size);
    out.put<int16_t>(m.params);
    out.put<float>(m.residual);
  }
  out.end_section(version, section);

  for (int i = 0; i < 2; ++i) {  // force plates, devices: none
    out.put<int32_t>(0);
    out.end_section(version, out.begin_section(version));
  }

  out.put<uint32_t>(frame.timecode);
  out.put<uint32_t>(frame.timecode_subframe);
  out.put<double>(frame.timestamp_s);
  out.put<uint64_t>(frame.stamp_mid_exposure);
  out.put<uint64_t>(frame.stamp_data_received);
  out.put<uint64_t>(frame.stamp_transmit);
  if (version.has_precise_timestamp()) {
    out.put<uint32_t>(frame.precise_seconds);
    out.put<uint32_t>(frame.precise_fraction);
  }
  out.put<int16_t>(frame.params);
  out.put<int32_t>(0);  // end of data
  out.finish();
}

}  // namespace skinstream::natnet
