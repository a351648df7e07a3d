#include "protocol/qtm/qtm_packet_framer.h"

#include <algorithm>
#include <cstring>

namespace skinstream::qtm {

std::span<unsigned char> PacketFramer::prepare(size_t size) {
  if (begin_ == end_) begin_ = end_ = 0;  // everything read: start again at the front
  if (buffer_.size() - end_ < size && begin_ > 0) {
    std::copy(buffer_.begin() + static_cast<long>(begin_), buffer_.begin() + static_cast<long>(end_),
              buffer_.begin());
    end_ -= begin_;
    begin_ = 0;
  }
  if (buffer_.size() - end_ < size) buffer_.resize(end_ + size);
  return {buffer_.data() + end_, size};
}

void PacketFramer::commit(size_t size) { end_ = std::min(end_ + size, buffer_.size()); }

void PacketFramer::feed(Bytes bytes) {
  const auto room = prepare(bytes.size());
  std::copy(bytes.begin(), bytes.end(), room.begin());
  commit(bytes.size());
}

void PacketFramer::reserve(size_t bytes) {
  if (buffer_.size() < bytes) buffer_.resize(bytes);
}

PacketFramer::Status PacketFramer::next(Bytes& out_packet) {
  if (!error_.empty()) return Status::Error;
  if (end_ - begin_ < kHeaderBytes) return Status::NeedMore;
  uint32_t size = 0;
  std::memcpy(&size, buffer_.data() + begin_, 4);
  // Judged from the header alone, before waiting for a body that may never come.
  if (size < kHeaderBytes || size > max_bytes_) {
    error_ = "packet size " + std::to_string(size) + " is outside 8.." + std::to_string(max_bytes_) + " bytes";
    return Status::Error;
  }
  if (end_ - begin_ < size) return Status::NeedMore;
  out_packet = Bytes(buffer_.data() + begin_, size);
  begin_ += size;
  return Status::Packet;
}

void PacketFramer::reset() {
  begin_ = end_ = 0;
  error_.clear();
}

}  // namespace skinstream::qtm
