#include "protocol/qtm/qtm_packet_framer.h"

#include <cstring>

namespace skinstream::qtm {

PacketFramer::Status PacketFramer::next(Bytes& out_packet) {
  if (!error_.empty()) return Status::Error;
  const Bytes unread = stream_.unread();
  if (unread.size() < kHeaderBytes) return Status::NeedMore;
  uint32_t size = 0;
  std::memcpy(&size, unread.data(), 4);
  // Judged from the header alone, before waiting for a body that may never come.
  if (size < kHeaderBytes || size > max_bytes_) {
    error_ =
        "packet size " + std::to_string(size) + " is outside 8.." + std::to_string(max_bytes_) + " bytes";
    return Status::Error;
  }
  if (unread.size() < size) return Status::NeedMore;
  out_packet = unread.first(size);
  stream_.consume(size);
  return Status::Packet;
}

void PacketFramer::reset() {
  stream_.clear();
  error_.clear();
}

}  // namespace skinstream::qtm
