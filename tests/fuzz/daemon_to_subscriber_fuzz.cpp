// What the daemon sends a subscriber (MeshInfo, Model, Frame, Status, Packed; Hello and Ack too), in
// versions 1 and 2, as a renderer reads it: the whole input as one message through decode_header
// and the decoder of its type and version, and as a stream through the StreamDecoder. Only
// DecodeError may be thrown, with a one-line reason; view_frame, decode_frame_info and
// decode_frame accept the same frames and agree on their FrameInfo, a decoded Model
// validates, and what a Packed message holds goes through its own type's decoder.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/packed_message.h"
#include "protocol/subscriber/subscriber_model.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace subscriber = skinstream::subscriber;

namespace {

bool same(const subscriber::FrameTimecode& a, const subscriber::FrameTimecode& b) {
  return a.hours == b.hours && a.minutes == b.minutes && a.seconds == b.seconds && a.frames == b.frames &&
         a.subframe == b.subframe && a.subframes_per_frame == b.subframes_per_frame &&
         std::memcmp(&a.rate_hz, &b.rate_hz, sizeof(float)) == 0 && a.flags == b.flags;
}

bool same(const subscriber::FrameInfo& a, const subscriber::FrameInfo& b) {
  return a.frame_number == b.frame_number && a.flags == b.flags && a.source_time_ns == b.source_time_ns &&
         a.receive_time_ns == b.receive_time_ns && a.publish_time_ns == b.publish_time_ns && a.vertex_count == b.vertex_count &&
         a.marker_count == b.marker_count && a.markers_filled == b.markers_filled && a.markers_relabelled == b.markers_relabelled &&
         a.pipeline_dropped == b.pipeline_dropped && a.subscriber_dropped == b.subscriber_dropped && same(a.timecode, b.timecode);
}

template <typename Decode>
bool decode_or_refuse(Decode&& decode) {
  try {
    decode();
    return true;
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
    return false;
  }
}

void decode_frame_every_way(std::span<const unsigned char> payload, uint16_t version) {
  std::optional<subscriber::FrameInfo> viewed, decoded, info;
  decode_or_refuse([&] { viewed = subscriber::view_frame(payload, version).info; });
  decode_or_refuse([&] { info = subscriber::decode_frame_info(payload, version); });
  decode_or_refuse([&] { decoded = subscriber::decode_frame(payload, version).info; });
  if (viewed.has_value() != info.has_value() || (viewed && !same(*viewed, *info))) std::abort();
  if (decoded && (!viewed || !same(*decoded, *viewed))) std::abort();  // decode_frame checks more, never less
}

void decode_payload(subscriber::MessageType type, uint16_t version, std::span<const unsigned char> payload) {
  switch (type) {
    case subscriber::MessageType::Hello: decode_or_refuse([&] { subscriber::decode_hello(payload, version); }); break;
    case subscriber::MessageType::Ack: decode_or_refuse([&] { subscriber::decode_ack(payload); }); break;
    case subscriber::MessageType::MeshInfo: decode_or_refuse([&] { subscriber::decode_mesh_info(payload, version); }); break;
    case subscriber::MessageType::Status: decode_or_refuse([&] { subscriber::decode_status(payload, version); }); break;
    case subscriber::MessageType::Frame: decode_frame_every_way(payload, version); break;
    case subscriber::MessageType::Model:
      decode_or_refuse([&] {
        if (!subscriber::decode_model(payload).validate().empty()) std::abort();
      });
      break;
    case subscriber::MessageType::Packed: {
      std::optional<subscriber::Unpacked> unpacked;
      decode_or_refuse([&] { unpacked = subscriber::decode_packed(payload, 1u << 24); });
      if (unpacked) {
        if (unpacked->type != subscriber::MessageType::MeshInfo &&
            unpacked->type != subscriber::MessageType::Model)
          std::abort();
        decode_payload(unpacked->type, subscriber::kVersion2, unpacked->payload);
      }
      break;
    }
  }
}

constexpr subscriber::MessageType kTypes[] = {
    subscriber::MessageType::Hello,  subscriber::MessageType::MeshInfo, subscriber::MessageType::Frame,
    subscriber::MessageType::Status, subscriber::MessageType::Ack,      subscriber::MessageType::Model,
    subscriber::MessageType::Packed};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const unsigned char> bytes(data, size);
  decode_or_refuse([&] {
    const subscriber::MessageHeader header = subscriber::decode_header(bytes);
    if (bytes.size() - subscriber::kHeaderBytes == header.payload_bytes)
      decode_payload(header.type, header.version, bytes.subspan(subscriber::kHeaderBytes));
  });
  // Each decoder in each version on the bytes after a header, whatever the header says.
  if (bytes.size() >= subscriber::kHeaderBytes)
    for (const uint16_t version : {subscriber::kVersion1, subscriber::kVersion2})
      for (const subscriber::MessageType type : kTypes) decode_payload(type, version, bytes.subspan(subscriber::kHeaderBytes));
  const size_t piece = 1 + size % 64;  // from the length, so a seed stays a whole message
  subscriber::StreamDecoder decoder(1u << 20);
  decode_or_refuse([&] {
    for (size_t fed = 0; fed < bytes.size(); fed += piece) {
      decoder.feed(bytes.subspan(fed, std::min(piece, bytes.size() - fed)));
      while (const auto message = decoder.next()) decode_payload(message->type, message->version, message->payload);
    }
  });
  return 0;
}
