#pragma once
// Cuts a QTM RT byte stream (TCP) into whole packets. Bytes go in as they arrive, in any pieces;
// whole packets come out. A size field below the header or above the limit stops the stream with
// a one-line reason: the stream cannot be resynchronised after it and must be closed. The bytes
// wait in a StreamBuffer, so a framer fed packets of steady size stops allocating.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/qtm/qtm_rt.h"
#include "protocol/stream_buffer.h"

namespace skinstream::qtm {

class PacketFramer {
 public:
  enum class Status { NeedMore, Packet, Error };

  explicit PacketFramer(uint32_t max_packet_bytes = kMaxPacketBytes) : max_bytes_(max_packet_bytes) {}

  // Room for `size` more bytes (a socket reads straight into it); then commit what was written.
  std::span<unsigned char> prepare(size_t size) { return stream_.prepare(size); }
  void commit(size_t size) { stream_.commit(size); }
  void feed(Bytes bytes) { stream_.feed(bytes); }  // prepare + copy + commit
  void reserve(size_t bytes) {
    stream_.reserve(bytes);
  }  // sizes (and touches) the buffer now, so it need not grow later

  // The next whole packet, header included; valid until the next prepare(), feed() or next().
  Status next(Bytes& out_packet);

  const std::string& error() const { return error_; }
  size_t buffered() const { return stream_.buffered(); }
  void reset();  // forget everything, an error included (a new connection)

 private:
  uint32_t max_bytes_;
  StreamBuffer stream_;
  std::string error_;
};

}  // namespace skinstream::qtm
