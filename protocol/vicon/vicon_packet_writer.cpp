#include "protocol/vicon/vicon_packet_writer.h"

#include <cstring>
#include <string>

namespace skinstream::vicon {

template <typename T>
void PacketWriter::put(T value) {
  static_assert(std::is_arithmetic_v<T>);
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));  // the wire is native little-endian, as the hosts are
  bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
}

void PacketWriter::put_string(const std::string& s) {
  put<uint32_t>(static_cast<uint32_t>(s.size()));
  bytes_.insert(bytes_.end(), s.begin(), s.end());
}

void PacketWriter::begin() {
  bytes_.clear();
  put<uint32_t>(kPacketMagic);
  put<uint32_t>(0);  // length, patched by finish()
}

size_t PacketWriter::begin_object(uint32_t type) {
  put<uint32_t>(type);
  const size_t length_offset = bytes_.size();
  put<uint32_t>(0);
  return length_offset;
}

void PacketWriter::end_object(size_t length_offset) {
  const auto length = static_cast<uint32_t>(bytes_.size() - length_offset - sizeof(uint32_t));
  std::memcpy(bytes_.data() + length_offset, &length, sizeof(length));
}

std::span<const unsigned char> PacketWriter::finish() {
  const auto length = static_cast<uint32_t>(bytes_.size() - kPacketHeaderBytes);
  std::memcpy(bytes_.data() + 4, &length, sizeof(length));
  return {bytes_.data(), bytes_.size()};
}

void PacketWriter::add(const ObjectEnums& object) {
  const size_t at = begin_object(object_type::ObjectEnums);
  put<uint32_t>(static_cast<uint32_t>(object.types.size()));
  for (uint32_t type : object.types) put<uint32_t>(type);
  end_object(at);
}

void PacketWriter::add(const RequestFrame& object) {
  const size_t at = begin_object(object_type::RequestFrame);
  put<uint8_t>(object.streaming ? 1 : 0);
  end_object(at);
}

void PacketWriter::add(const RequestNextFrame& object) {
  const size_t at = begin_object(object_type::RequestNextFrame);
  put<uint32_t>(object.count);
  end_object(at);
}

void PacketWriter::add(const Ping& object) {
  const size_t at = begin_object(object_type::Ping);
  put<uint64_t>(object.id);
  end_object(at);
}

void PacketWriter::add(const StartMulticastSender& object) {
  const size_t at = begin_object(object_type::StartMulticastSender);
  put<uint32_t>(object.multicast_address);
  put<uint32_t>(object.source_address);
  put<uint16_t>(object.port);
  end_object(at);
}

void PacketWriter::add_stop_multicast_sender() { end_object(begin_object(object_type::StopMulticastSender)); }

void PacketWriter::add(const Contents& object) {
  const size_t at = begin_object(object_type::Contents);
  put<uint32_t>(static_cast<uint32_t>(object.table.size()));
  for (const auto& [type, value] : object.table) {
    put<uint32_t>(type);
    put<uint32_t>(value);
  }
  put<uint32_t>(static_cast<uint32_t>(object.unchanged.size()));
  for (uint32_t type : object.unchanged) put<uint32_t>(type);
  end_object(at);
}

void PacketWriter::add(const Filter& object) {
  const size_t at = begin_object(object_type::Filter);
  put<uint32_t>(static_cast<uint32_t>(object.filters.size()));
  for (const auto& [type, ids] : object.filters) {
    put<uint32_t>(type);
    put<uint32_t>(static_cast<uint32_t>(ids.size()));
    for (uint32_t id : ids) put<uint32_t>(id);
  }
  end_object(at);
}

void PacketWriter::add(const StreamInfo& object) {
  const size_t at = begin_object(object_type::StreamInfo);
  put<int64_t>(object.frame_period_ticks);
  end_object(at);
}

void PacketWriter::add(const SubjectInfo& object) {
  const size_t at = begin_object(object_type::SubjectInfo);
  put<uint32_t>(object.subject_id);
  put_string(object.name);
  put<uint32_t>(static_cast<uint32_t>(object.segments.size()));
  for (const SubjectSegment& segment : object.segments) {
    put<uint32_t>(segment.parent_id);
    put<uint32_t>(segment.segment_id);
    for (float b : segment.bounds) put<float>(b);
    put_string(segment.name);
  }
  put<uint32_t>(static_cast<uint32_t>(object.markers.size()));
  for (const SubjectMarker& marker : object.markers) {
    put<uint32_t>(marker.marker_id);
    put_string(marker.name);
  }
  put<uint32_t>(static_cast<uint32_t>(object.attachments.size()));
  for (const SubjectAttachment& attachment : object.attachments) {
    put<uint32_t>(attachment.marker_id);
    put<uint32_t>(attachment.segment_id);
  }
  end_object(at);
}

void PacketWriter::add(const FrameInfo& object) {
  const size_t at = begin_object(object_type::FrameInfo);
  put<uint32_t>(object.frame_id);
  end_object(at);
}

void PacketWriter::add(const Timecode& object) {
  const size_t at = begin_object(object_type::Timecode);
  put<uint8_t>(object.hours);
  put<uint8_t>(object.minutes);
  put<uint8_t>(object.seconds);
  put<uint8_t>(object.frames);
  put<uint16_t>(object.subframes);
  put<uint16_t>(object.subframes_per_frame);
  put<uint32_t>(object.standard);
  put<uint32_t>(object.user_bits);
  put<uint8_t>(object.field_flag);
  end_object(at);
}

void PacketWriter::add(std::span<const LabeledRecon> recons) {
  const size_t at = begin_object(object_type::LabeledRecons);
  put<uint32_t>(static_cast<uint32_t>(recons.size()));
  for (const LabeledRecon& r : recons) {
    put<uint32_t>(r.subject_id);
    put<uint32_t>(r.marker_id);
    put<double>(r.radius);
    for (double v : r.position) put<double>(v);
    for (double v : r.covariance) put<double>(v);
    put<uint32_t>(r.trajectory_id);
  }
  end_object(at);
}

void PacketWriter::add(std::span<const UnlabeledRecon> recons) {
  const size_t at = begin_object(object_type::UnlabeledRecons);
  put<uint32_t>(static_cast<uint32_t>(recons.size()));
  for (const UnlabeledRecon& r : recons) {
    put<double>(r.radius);
    for (double v : r.position) put<double>(v);
    for (double v : r.covariance) put<double>(v);
    put<uint32_t>(r.trajectory_id);
  }
  end_object(at);
}

void PacketWriter::add_raw(uint32_t type, std::span<const unsigned char> payload) {
  const size_t at = begin_object(type);
  bytes_.insert(bytes_.end(), payload.begin(), payload.end());
  end_object(at);
}

}  // namespace skinstream::vicon
