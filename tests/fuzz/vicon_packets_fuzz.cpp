// Vicon DataStream bytes as a TCP client and a UDP receiver meet them: the framer cuts the
// stream, fed in pieces of 1 to 64 bytes (from the input's length, so seeds stay whole packets), and every object of each
// packet goes through its decoder (as the frame assembler decodes them); the whole input is also
// decoded as one datagram. Whatever the bytes, a refusal is one line, and the framer and the
// whole-packet decoder agree on what they accept.
#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz/one_line_file_error.h"
#include "protocol/vicon/vicon_packet_framer.h"
#include "protocol/vicon/vicon_packet_reader.h"

namespace vicon = skinstream::vicon;

namespace {

void expect_refusal_is_one_line(bool ok, const std::string& error) {
  if (!ok) skinstream::fuzz::expect_one_printable_line(error);
}

void decode_objects(const std::vector<vicon::ObjectView>& objects) {
  std::string error;
  for (const vicon::ObjectView& o : objects) {
    bool ok = true;
    switch (o.type) {
      case vicon::object_type::StreamInfo: { vicon::StreamInfo v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::SubjectInfo: { vicon::SubjectInfo v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::FrameInfo: { vicon::FrameInfo v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::LabeledRecons: { std::vector<vicon::LabeledRecon> v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::UnlabeledRecons: { std::vector<vicon::UnlabeledRecon> v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::Timecode: { vicon::Timecode v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::ObjectEnums: { vicon::ObjectEnums v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::Contents: { vicon::Contents v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::Filter: { vicon::Filter v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::RequestFrame: { vicon::RequestFrame v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::RequestNextFrame: { vicon::RequestNextFrame v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::Ping: { vicon::Ping v; ok = vicon::decode(o.payload, v, error); break; }
      case vicon::object_type::StartMulticastSender: { vicon::StartMulticastSender v; ok = vicon::decode(o.payload, v, error); break; }
      default: break;
    }
    expect_refusal_is_one_line(ok, error);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const size_t piece = 1 + size % 64;
  const vicon::Bytes stream(data, size);

  vicon::DecodedPacket whole;
  std::string whole_error;
  const bool whole_ok = vicon::decode_packet(stream, whole, whole_error);
  expect_refusal_is_one_line(whole_ok, whole_error);

  vicon::PacketFramer framer(1u << 20);
  vicon::Bytes packet;
  size_t fed = 0, packets = 0;
  bool refused = false;
  while (fed < stream.size() && !refused) {
    const size_t n = std::min(piece, stream.size() - fed);
    framer.feed(stream.subspan(fed, n));
    fed += n;
    for (;;) {
      const vicon::PacketFramer::Status status = framer.next(packet);
      if (status == vicon::PacketFramer::Status::NeedMore) break;
      if (status == vicon::PacketFramer::Status::Error) {
        skinstream::fuzz::expect_one_printable_line(framer.error());
        refused = true;
        break;
      }
      ++packets;
      decode_objects(framer.objects());
    }
  }
  // One whole packet is what both take: split the same way, so the framer cuts exactly it.
  if (whole_ok && (refused || packets != 1 || framer.buffered() != 0)) std::abort();
  return 0;
}
