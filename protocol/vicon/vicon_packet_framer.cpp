#include "protocol/vicon/vicon_packet_framer.h"

#include <cstdio>
#include <cstring>

namespace skinstream::vicon {

std::span<unsigned char> PacketFramer::prepare(size_t size) {
  if (begin_ > 0) {  // move the unread tail to the front before growing
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (buffer_.size() < end_ + size) buffer_.resize(end_ + size);
  return {buffer_.data() + end_, size};
}

void PacketFramer::reserve(size_t bytes) {
  if (buffer_.size() < bytes) buffer_.resize(bytes);  // zero-filled: every page touched once, here
}

void PacketFramer::commit(size_t size) { end_ = std::min(end_ + size, buffer_.size()); }

void PacketFramer::feed(Bytes bytes) {
  const auto room = prepare(bytes.size());
  if (!bytes.empty()) std::memcpy(room.data(), bytes.data(), bytes.size());
  commit(bytes.size());
}

PacketFramer::Status PacketFramer::fail(std::string reason) {
  error_ = std::move(reason);
  objects_.clear();
  return Status::Error;
}

PacketFramer::Status PacketFramer::next(Bytes& out_packet) {
  if (!error_.empty()) return Status::Error;
  const size_t available = end_ - begin_;
  if (available < kPacketHeaderBytes) return Status::NeedMore;
  const unsigned char* head = buffer_.data() + begin_;
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
  begin_ += packet.size();
  out_packet = packet;
  return Status::Packet;
}

void PacketFramer::reset() {
  begin_ = end_ = 0;
  objects_.clear();
  error_.clear();
}

}  // namespace skinstream::vicon
