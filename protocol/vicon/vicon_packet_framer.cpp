#include "protocol/vicon/vicon_packet_framer.h"

#include <cstdio>
#include <cstring>

namespace skinstream::vicon {

PacketFramer::Status PacketFramer::fail(std::string reason) {
  error_ = std::move(reason);
  objects_.clear();
  return Status::Error;
}

PacketFramer::Status PacketFramer::next(Bytes& out_packet) {
  if (!error_.empty()) return Status::Error;
  const Bytes unread = stream_.unread();
  const size_t available = unread.size();
  if (available < kPacketHeaderBytes) return Status::NeedMore;
  const unsigned char* head = unread.data();
  uint32_t magic = 0, length = 0;
  std::memcpy(&magic, head, 4);
  std::memcpy(&length, head + 4, 4);
  // Judged from the header alone, before waiting for a body that may never come.
  if (magic != kPacketMagic) {
    char hex[16];
    std::snprintf(hex, sizeof(hex), "0x%08X", magic);
    return fail(std::string("bad packet magic ") + hex + " (expected 0x1A2B0001)");
  }
  if (length > max_length_)
    return fail("packet length " + std::to_string(length) + " exceeds the limit of " + std::to_string(max_length_) +
                " bytes");
  if (available - kPacketHeaderBytes < length) return Status::NeedMore;
  const Bytes packet(head, kPacketHeaderBytes + length);
  std::string reason;
  if (!split_objects(packet, objects_, reason, limits_)) return fail(std::move(reason));
  stream_.consume(packet.size());
  out_packet = packet;
  return Status::Packet;
}

void PacketFramer::reset() {
  stream_.clear();
  objects_.clear();
  error_.clear();
}

}  // namespace skinstream::vicon
