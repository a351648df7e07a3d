#include "protocol/subscriber/packed_message.h"

#include <zlib.h>

#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>

#include "protocol/byte_reader.h"

namespace skinstream::subscriber {
namespace {

// Deflate makes at most 1032 bytes of one (RFC 1951's longest match in its shortest code); a
// stream claiming more is refused before anything is allocated for it.
constexpr size_t kMostInflatedPerByte = 1032;

struct Layout {
  size_t head_bytes = 0;
  size_t count_offset = 0;  // in the head: the u32 N of the 3N-value array after the head
  const char* count_name = "";
};

std::optional<Layout> layout_of(MessageType type) {
  if (type == MessageType::MeshInfo) return Layout{kPackedMeshInfoHeadBytes, 4, "face count"};
  if (type == MessageType::Model) return Layout{kPackedModelHeadBytes, 0, "vertex count"};
  return std::nullopt;
}

uint32_t u32_at(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Each value less the value three before it, then the values' byte 0s, byte 1s, byte 2s, byte 3s.
void code_array(std::span<unsigned char> bytes) {
  const size_t count = bytes.size() / 4;
  std::vector<uint32_t> values(count);
  if (count > 0) std::memcpy(values.data(), bytes.data(), count * 4);
  for (size_t i = count; i-- > 3;) values[i] -= values[i - 3];
  for (size_t i = 0; i < count; ++i)
    for (size_t plane = 0; plane < 4; ++plane)
      bytes[plane * count + i] = static_cast<unsigned char>(values[i] >> (8 * plane));
}

void uncode_array(std::span<unsigned char> bytes) {
  const size_t count = bytes.size() / 4;
  std::vector<uint32_t> values(count);
  for (size_t i = 0; i < count; ++i) {
    uint32_t v = 0;
    for (size_t plane = 0; plane < 4; ++plane)
      v |= static_cast<uint32_t>(bytes[plane * count + i]) << (8 * plane);
    values[i] = i >= 3 ? v + values[i - 3] : v;
  }
  if (count > 0) std::memcpy(bytes.data(), values.data(), count * 4);
}

}  // namespace

std::vector<unsigned char> encode_packed(MessageType type, std::span<const unsigned char> payload,
                                         int level) {
  const std::optional<Layout> layout = layout_of(type);
  if (!layout)
    throw std::invalid_argument(std::string("encode_packed: a ") + to_string(type) + " is not packed");
  if (payload.size() < layout->head_bytes)
    throw std::invalid_argument("encode_packed: payload shorter than its counts");
  const size_t array_bytes = size_t{12} * u32_at(payload.data() + layout->count_offset);
  std::vector<unsigned char> rest(payload.begin() + static_cast<std::ptrdiff_t>(layout->head_bytes),
                                  payload.end());
  if (array_bytes > rest.size())
    throw std::invalid_argument(std::string("encode_packed: its ") + layout->count_name + " does not fit");
  code_array(std::span(rest).first(array_bytes));

  uLongf stream_bytes = compressBound(static_cast<uLong>(rest.size()));
  std::vector<unsigned char> out(kHeaderBytes + kPackedFieldsBytes + layout->head_bytes + stream_bytes);
  unsigned char* fields = out.data() + kHeaderBytes;
  const uint16_t packed_type = static_cast<uint16_t>(type), reserved = 0;
  const uint32_t unpacked = static_cast<uint32_t>(payload.size());
  std::memcpy(fields, &packed_type, 2);
  std::memcpy(fields + 2, &reserved, 2);
  std::memcpy(fields + 4, &unpacked, 4);
  std::memcpy(fields + kPackedFieldsBytes, payload.data(), layout->head_bytes);
  unsigned char* stream = fields + kPackedFieldsBytes + layout->head_bytes;
  if (compress2(stream, &stream_bytes, rest.data(), static_cast<uLong>(rest.size()), level) != Z_OK)
    throw std::invalid_argument("encode_packed: zlib could not deflate it");
  out.resize(static_cast<size_t>(stream - out.data()) + stream_bytes);
  write_header(MessageType::Packed, kVersion2, out.size() - kHeaderBytes,
               std::span(out).first<kHeaderBytes>());
  return out;
}

Unpacked decode_packed(std::span<const unsigned char> payload, uint32_t max_payload) {
  ByteReader r(payload);
  const uint16_t packed_type = r.get<uint16_t>("packed type");
  const uint16_t reserved = r.get<uint16_t>("reserved");
  const uint32_t unpacked_bytes = r.get<uint32_t>("unpacked size");
  if (!r.ok()) throw DecodeError("Packed: " + r.error().message());
  const std::optional<Layout> layout = layout_of(static_cast<MessageType>(packed_type));
  if (!layout)
    throw DecodeError("Packed: holds a message of type " + std::to_string(packed_type) +
                      " (only MeshInfo and Model are packed)");
  if (reserved != 0) throw DecodeError("Packed: reserved field is " + std::to_string(reserved) + ", not 0");
  if (unpacked_bytes > max_payload)
    throw DecodeError("Packed: unpacked size " + std::to_string(unpacked_bytes) + " over the limit of " +
                      std::to_string(max_payload));
  const std::span<const unsigned char> head = r.take(layout->head_bytes, "packed head");
  if (!r.ok()) throw DecodeError("Packed: " + r.error().message());
  if (unpacked_bytes < layout->head_bytes)
    throw DecodeError("Packed: unpacked size " + std::to_string(unpacked_bytes) + " shorter than its counts");
  const size_t rest_bytes = unpacked_bytes - layout->head_bytes;
  const size_t stream_bytes = r.remaining();
  if (rest_bytes > stream_bytes * kMostInflatedPerByte + 64)
    throw DecodeError("Packed: " + std::to_string(stream_bytes) + " deflated bytes cannot make " +
                      std::to_string(rest_bytes));
  const size_t array_bytes = size_t{12} * u32_at(head.data() + layout->count_offset);
  if (array_bytes > rest_bytes)
    throw DecodeError(std::string("Packed: its ") + layout->count_name + " needs " +
                      std::to_string(array_bytes) + " bytes, the unpacked size leaves " +
                      std::to_string(rest_bytes));

  Unpacked out{static_cast<MessageType>(packed_type), std::vector<unsigned char>(unpacked_bytes)};
  std::memcpy(out.payload.data(), head.data(), head.size());
  z_stream z{};
  if (inflateInit(&z) != Z_OK) throw DecodeError("Packed: zlib could not start inflating");
  z.next_in = const_cast<unsigned char*>(r.here());
  z.avail_in = static_cast<uInt>(stream_bytes);
  z.next_out = out.payload.data() + layout->head_bytes;
  z.avail_out = static_cast<uInt>(rest_bytes);
  const int result = inflate(&z, Z_FINISH);
  const size_t made = rest_bytes - z.avail_out, left = z.avail_in;
  inflateEnd(&z);
  if (result != Z_STREAM_END)
    throw DecodeError(std::string("Packed: the deflated stream ") +
                      (result == Z_BUF_ERROR
                           ? "makes more than the unpacked size " + std::to_string(rest_bytes) +
                                 " or ends early (" + std::to_string(made) + " bytes made)"
                           : std::string("is corrupt (") + (z.msg ? z.msg : "zlib error") + ")"));
  if (made != rest_bytes)
    throw DecodeError("Packed: the deflated stream makes " + std::to_string(made) +
                      " bytes, the unpacked size says " + std::to_string(rest_bytes));
  if (left != 0) throw DecodeError("Packed: " + std::to_string(left) + " bytes after the deflated stream");
  uncode_array(std::span(out.payload).subspan(layout->head_bytes, array_bytes));
  return out;
}

size_t plain_message_bytes(std::span<const unsigned char> packed_message) {
  if (packed_message.size() < kHeaderBytes + kPackedFieldsBytes)
    throw std::invalid_argument("plain_message_bytes: not a Packed message");
  return kHeaderBytes + u32_at(packed_message.data() + kHeaderBytes + 4);
}

void set_packed_source_rate(std::span<unsigned char> packed_mesh_info, float rate_hz) {
  if (packed_mesh_info.size() < kPackedSourceRateOffset + 4)
    throw std::invalid_argument("set_packed_source_rate: not a packed MeshInfo");
  std::memcpy(packed_mesh_info.data() + kPackedSourceRateOffset, &rate_hz, 4);
}

float packed_source_rate(std::span<const unsigned char> packed_mesh_info) {
  if (packed_mesh_info.size() < kPackedSourceRateOffset + 4)
    throw std::invalid_argument("packed_source_rate: not a packed MeshInfo");
  float rate;
  std::memcpy(&rate, packed_mesh_info.data() + kPackedSourceRateOffset, 4);
  return rate;
}

}  // namespace skinstream::subscriber
