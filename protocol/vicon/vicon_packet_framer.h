#pragma once
// Cuts a TCP byte stream into whole Vicon DataStream packets. Bytes go in as they arrive (in any
// pieces); whole packets come out, already split into objects. A bad magic, a length over the
// limit, a truncated object header or an object overrunning its packet stops the stream with a
// one-line reason: after an error the stream cannot be resynchronised and must be closed.
// The bytes wait in a StreamBuffer, so a framer fed frames of steady size stops allocating.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/stream_buffer.h"
#include "protocol/vicon/vicon_packet_reader.h"

namespace skinstream::vicon {

class PacketFramer {
 public:
  enum class Status { NeedMore, Packet, Error };

  explicit PacketFramer(uint32_t max_packet_length = kMaxPacketLength, DescriptionLimits limits = {})
      : max_length_(max_packet_length), limits_(limits) {}

  // Room for `size` more bytes (e.g. a socket read straight into it); then commit what was written.
  std::span<unsigned char> prepare(size_t size) { return stream_.prepare(size); }
  void commit(size_t size) { stream_.commit(size); }
  void feed(Bytes bytes) { stream_.feed(bytes); }  // prepare + copy + commit

  // The next whole packet (header included) and its objects. Both stay valid until the next
  // prepare(), feed() or next().
  Status next(Bytes& out_packet);
  const std::vector<ObjectView>& objects() const { return objects_; }

  // Sizes the buffer now (and writes it, so its pages are resident): a reader that asks
  // prepare() for at most `bytes` minus the unread tail never grows it later, when a burst
  // leaves a partial packet behind a full read.
  void reserve(size_t bytes) { stream_.reserve(bytes); }

  const std::string& error() const { return error_; }
  size_t buffered() const { return stream_.buffered(); }
  size_t capacity() const { return stream_.capacity(); }
  void reset();  // forget everything, including an error (a new connection)

 private:
  Status fail(std::string reason);

  uint32_t max_length_;
  DescriptionLimits limits_;  // the subjects of a packet (split_objects)
  StreamBuffer stream_;
  std::vector<ObjectView> objects_;
  std::string error_;
};

}  // namespace skinstream::vicon
