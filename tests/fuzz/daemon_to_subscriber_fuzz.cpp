// What the daemon sends a subscriber (MeshInfo, Frame, Status; Hello and Ack too), as a renderer
// reads it: the whole input as one message through decode_header and every decode_*, and as a
// stream through the StreamDecoder. Only DecodeError may be thrown, with a one-line reason, and
// decode_frame_info agrees with decode_frame on every frame both accept.
#include <algorithm>
#include <cstdlib>
#include <optional>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber_stream.h"

namespace subscriber = skinstream::subscriber;

namespace {

bool same(const subscriber::FrameInfo& a, const subscriber::FrameInfo& b) {
  return a.frame_number == b.frame_number && a.flags == b.flags && a.source_time_ns == b.source_time_ns &&
         a.receive_time_ns == b.receive_time_ns && a.publish_time_ns == b.publish_time_ns && a.vertex_count == b.vertex_count &&
         a.marker_count == b.marker_count && a.markers_filled == b.markers_filled && a.markers_relabelled == b.markers_relabelled &&
         a.pipeline_dropped == b.pipeline_dropped && a.subscriber_dropped == b.subscriber_dropped;
}

template <typename Decode>
void decode_or_refuse(Decode&& decode) {
  try {
    decode();
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
  }
}

void decode_payload(subscriber::MessageType type, std::span<const unsigned char> payload) {
  switch (type) {
    case subscriber::MessageType::Hello: decode_or_refuse([&] { subscriber::decode_hello(payload); }); break;
    case subscriber::MessageType::Ack: decode_or_refuse([&] { subscriber::decode_ack(payload); }); break;
    case subscriber::MessageType::MeshInfo: decode_or_refuse([&] { subscriber::decode_mesh_info(payload); }); break;
    case subscriber::MessageType::Status: decode_or_refuse([&] { subscriber::decode_status(payload); }); break;
    case subscriber::MessageType::Frame: {
      std::optional<subscriber::FrameInfo> from_frame;
      decode_or_refuse([&] { from_frame = subscriber::decode_frame(payload).info; });
      try {
        const subscriber::FrameInfo info = subscriber::decode_frame_info(payload);
        if (from_frame && !same(info, *from_frame)) std::abort();
      } catch (const subscriber::DecodeError& e) {
        skinstream::fuzz::expect_one_printable_line(e.what());
        if (from_frame) std::abort();  // it checks less than decode_frame, never more
      }
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const unsigned char> bytes(data, size);
  decode_or_refuse([&] {
    const subscriber::MessageHeader header = subscriber::decode_header(bytes);
    if (bytes.size() - subscriber::kHeaderBytes == header.payload_bytes)
      decode_payload(header.type, bytes.subspan(subscriber::kHeaderBytes));
  });
  // Each decoder on the bytes after a header, whatever the header says.
  if (bytes.size() >= subscriber::kHeaderBytes)
    for (const auto type : {subscriber::MessageType::Hello, subscriber::MessageType::MeshInfo, subscriber::MessageType::Frame,
                            subscriber::MessageType::Status, subscriber::MessageType::Ack})
      decode_payload(type, bytes.subspan(subscriber::kHeaderBytes));
  const size_t piece = 1 + size % 64;  // from the length, so a seed stays a whole message
  subscriber::StreamDecoder decoder(1u << 20);
  decode_or_refuse([&] {
    for (size_t fed = 0; fed < bytes.size(); fed += piece) {
      decoder.feed(bytes.subspan(fed, std::min(piece, bytes.size() - fed)));
      while (const auto message = decoder.next()) decode_payload(message->type, message->payload);
    }
  });
  return 0;
}
