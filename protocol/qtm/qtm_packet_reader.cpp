#include "protocol/qtm/qtm_packet_reader.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "protocol/byte_reader.h"

namespace skinstream::qtm {
namespace {

bool refuse_packet(std::string& out_error, std::string reason) {
  out_error = std::move(reason);
  return false;
}

bool expect_type(Bytes packet, PacketType wanted, std::string& out_error) {
  uint32_t type = 0;
  if (!read_header(packet, type, out_error)) return false;
  if (type != static_cast<uint32_t>(wanted))
    return refuse_packet(out_error, std::string("expected a ") + packet_type_name(static_cast<uint32_t>(wanted)) +
                               " packet, got type " + std::to_string(type) + " (" + packet_type_name(type) + ")");
  return true;
}

// One 3D-family component's markers (body = what follows the 8-byte component header).
bool decode_markers(uint32_t type, Bytes body, DataFrame& out, std::string& out_error) {
  constexpr size_t kCountsBytes = 8;  // u32 count, u16 drop rate, u16 out-of-sync rate
  if (body.size() < kCountsBytes) return refuse_packet(out_error, "3D component of " + std::to_string(body.size()) +
                                                            " bytes is shorter than its marker count");
  ByteReader r(body);  // sizes checked before each read: none can fail
  const uint32_t count = r.get<uint32_t>("marker count");
  const bool unlabelled = type == component::k3dNoLabels || type == component::k3dNoLabelsResiduals;
  const bool residuals = type == component::k3dResiduals || type == component::k3dNoLabelsResiduals;
  const size_t marker_bytes = 12 + (unlabelled ? 4 : 0) + (residuals ? 4 : 0);
  const size_t data_bytes = body.size() - kCountsBytes;
  if (data_bytes % marker_bytes != 0 || data_bytes / marker_bytes != count)
    return refuse_packet(out_error, "3D component says " + std::to_string(count) + " markers of " +
                               std::to_string(marker_bytes) + " bytes but holds " + std::to_string(data_bytes) +
                               " bytes");
  out.drop_rate_2d = r.get<uint16_t>("2D drop rate");
  out.out_of_sync_rate_2d = r.get<uint16_t>("2D out-of-sync rate");
  if (unlabelled) {
    out.has_unlabelled = true;
    out.unlabelled.resize(count);
    for (UnlabelledMarker& m : out.unlabelled) {
      r.get_array(m.position.data(), 3, "marker position");
      if (residuals) r.skip(4, "marker residual");  // the residual comes before the id
      m.id = r.get<uint32_t>("marker id");
    }
  } else {
    out.has_labelled = true;
    out.labelled.resize(count);
    for (auto& position : out.labelled) {
      r.get_array(position.data(), 3, "marker position");
      if (residuals) r.skip(4, "marker residual");
    }
  }
  return true;
}

}  // namespace

const char* packet_type_name(uint32_t type) {
  switch (type) {
    case 0: return "Error";
    case 1: return "Command";
    case 2: return "XML";
    case 3: return "Data";
    case 4: return "NoMoreData";
    case 5: return "C3DFile";
    case 6: return "Event";
    case 7: return "Discover";
    case 8: return "QTMFile";
    default: return "unknown";
  }
}

bool read_header(Bytes packet, uint32_t& out_type, std::string& out_error) {
  if (packet.size() < kHeaderBytes)
    return refuse_packet(out_error, "packet of " + std::to_string(packet.size()) + " bytes is shorter than its 8-byte header");
  ByteReader r(packet);
  const uint32_t size = r.get<uint32_t>("packet size");
  if (size < kHeaderBytes) return refuse_packet(out_error, "packet size " + std::to_string(size) + " is less than its header");
  if (size > kMaxPacketBytes)
    return refuse_packet(out_error, "packet size " + std::to_string(size) + " exceeds the limit of " +
                               std::to_string(kMaxPacketBytes) + " bytes");
  if (size != packet.size())
    return refuse_packet(out_error, "packet size field says " + std::to_string(size) + " bytes but " +
                               std::to_string(packet.size()) + " were given");
  out_type = r.get<uint32_t>("packet type");
  return true;
}

bool decode_text(Bytes packet, std::string& out_text, std::string& out_error) {
  uint32_t type = 0;
  if (!read_header(packet, type, out_error)) return false;
  if (type != static_cast<uint32_t>(PacketType::Command) && type != static_cast<uint32_t>(PacketType::Error) &&
      type != static_cast<uint32_t>(PacketType::Xml))
    return refuse_packet(out_error, std::string("a ") + packet_type_name(type) + " packet holds no text");
  const auto* text = reinterpret_cast<const char*>(packet.data() + kHeaderBytes);
  const size_t length = packet.size() - kHeaderBytes;
  out_text.assign(text, strnlen(text, length));
  return true;
}

bool decode_event(Bytes packet, Event& out_event, std::string& out_error) {
  if (!expect_type(packet, PacketType::Event, out_error)) return false;
  if (packet.size() != kHeaderBytes + 1)
    return refuse_packet(out_error, "event packet of " + std::to_string(packet.size()) + " bytes (expected 9)");
  out_event = static_cast<Event>(packet[kHeaderBytes]);
  return true;
}

bool decode_data(Bytes packet, DataFrame& out, std::string& out_error) {
  if (!expect_type(packet, PacketType::Data, out_error)) return false;
  constexpr size_t kFrameHeaderBytes = 16;  // i64 timestamp, u32 frame number, u32 component count
  if (packet.size() < kHeaderBytes + kFrameHeaderBytes)
    return refuse_packet(out_error, "data packet of " + std::to_string(packet.size()) + " bytes is shorter than its header");
  ByteReader r(packet.subspan(kHeaderBytes));  // sizes checked before each read: none can fail
  out.timestamp_us = r.get<int64_t>("timestamp");
  out.frame_number = r.get<uint32_t>("frame number");
  const uint32_t components = r.get<uint32_t>("component count");
  out.has_labelled = out.has_unlabelled = false;
  out.drop_rate_2d = out.out_of_sync_rate_2d = 0;
  out.labelled.clear();
  out.unlabelled.clear();
  out.skipped_components = 0;

  for (uint32_t i = 0; i < components; ++i) {
    const size_t left = r.remaining();
    if (left < 8)
      return refuse_packet(out_error, "data packet ends inside the header of component " + std::to_string(i + 1) + " of " +
                                 std::to_string(components));
    const uint32_t size = r.get<uint32_t>("component size");
    const uint32_t type = r.get<uint32_t>("component type");
    if (size < 8 || size > left)
      return refuse_packet(out_error, "component " + std::to_string(i + 1) + " (type " + std::to_string(type) + ") says " +
                                 std::to_string(size) + " bytes with " + std::to_string(left) + " left");
    const Bytes body = r.take(size - 8, "component");
    switch (type) {
      case component::k3d:
      case component::k3dResiduals:
        if (out.has_labelled) return refuse_packet(out_error, "data packet has two labelled 3D components");
        if (!decode_markers(type, body, out, out_error)) return false;
        break;
      case component::k3dNoLabels:
      case component::k3dNoLabelsResiduals:
        if (out.has_unlabelled) return refuse_packet(out_error, "data packet has two unlabelled 3D components");
        if (!decode_markers(type, body, out, out_error)) return false;
        break;
      default:
        ++out.skipped_components;
        break;
    }
  }
  if (r.remaining() != 0)
    return refuse_packet(out_error, "data packet has " + std::to_string(r.remaining()) + " bytes after its " +
                                        std::to_string(components) + " components");
  return true;
}

bool decode_packet(Bytes packet, Packet& out, std::string& out_error) {
  if (!read_header(packet, out.type, out_error)) return false;
  switch (static_cast<PacketType>(out.type)) {
    case PacketType::Error:
    case PacketType::Command:
    case PacketType::Xml:
      return decode_text(packet, out.text, out_error);
    case PacketType::Event:
      return decode_event(packet, out.event, out_error);
    case PacketType::Data:
      return decode_data(packet, out.data, out_error);
    case PacketType::NoMoreData:
      if (packet.size() != kHeaderBytes) return refuse_packet(out_error, "NoMoreData packet with a body");
      return true;
    default:
      return refuse_packet(out_error, "unsupported packet type " + std::to_string(out.type) + " (" +
                                 packet_type_name(out.type) + ")");
  }
}

}  // namespace skinstream::qtm
