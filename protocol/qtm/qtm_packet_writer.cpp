#include "protocol/qtm/qtm_packet_writer.h"

#include <cstring>

namespace skinstream::qtm {
namespace {

void store_u32(unsigned char* p, uint32_t value) { std::memcpy(p, &value, 4); }

std::vector<unsigned char> header_only(PacketType type, size_t body_bytes) {
  std::vector<unsigned char> bytes(kHeaderBytes + body_bytes);
  store_u32(bytes.data(), static_cast<uint32_t>(bytes.size()));
  store_u32(bytes.data() + 4, static_cast<uint32_t>(type));
  return bytes;
}

}  // namespace

std::vector<unsigned char> encode_text(PacketType type, std::string_view text) {
  std::vector<unsigned char> bytes = header_only(type, text.size() + 1);  // + NUL (zero already)
  std::memcpy(bytes.data() + kHeaderBytes, text.data(), text.size());
  return bytes;
}

std::vector<unsigned char> encode_event(Event event) {
  std::vector<unsigned char> bytes = header_only(PacketType::Event, 1);
  bytes[kHeaderBytes] = static_cast<unsigned char>(event);
  return bytes;
}

std::vector<unsigned char> encode_no_more_data() { return header_only(PacketType::NoMoreData, 0); }

template <typename T>
void DataPacketWriter::put(T value) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
}

void DataPacketWriter::begin(int64_t timestamp_us, uint32_t frame_number) {
  bytes_.clear();
  components_ = 0;
  put<uint32_t>(0);  // size, filled in by finish()
  put<uint32_t>(static_cast<uint32_t>(PacketType::Data));
  put<int64_t>(timestamp_us);
  put<uint32_t>(frame_number);
  put<uint32_t>(0);  // component count, filled in by finish()
}

size_t DataPacketWriter::begin_component(uint32_t type, uint32_t count) {
  const size_t start = bytes_.size();
  put<uint32_t>(0);  // size, filled in by end_component()
  put<uint32_t>(type);
  put<uint32_t>(count);
  put<uint16_t>(0);  // 2D drop rate: a replay drops nothing
  put<uint16_t>(0);  // out-of-sync rate
  ++components_;
  return start;
}

void DataPacketWriter::end_component(size_t start) {
  store_u32(bytes_.data() + start, static_cast<uint32_t>(bytes_.size() - start));
}

void DataPacketWriter::add_labelled(std::span<const std::array<float, 3>> positions) {
  const size_t start = begin_component(component::k3d, static_cast<uint32_t>(positions.size()));
  for (const auto& p : positions)
    for (float v : p) put<float>(v);
  end_component(start);
}

void DataPacketWriter::add_unlabelled(std::span<const UnlabelledMarker> markers) {
  const size_t start = begin_component(component::k3dNoLabels, static_cast<uint32_t>(markers.size()));
  for (const UnlabelledMarker& m : markers) {
    for (float v : m.position) put<float>(v);
    put<uint32_t>(m.id);
  }
  end_component(start);
}

std::span<const unsigned char> DataPacketWriter::finish() {
  store_u32(bytes_.data(), static_cast<uint32_t>(bytes_.size()));
  store_u32(bytes_.data() + kHeaderBytes + 12, components_);
  return bytes_;
}

}  // namespace skinstream::qtm
