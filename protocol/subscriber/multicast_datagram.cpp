#include "protocol/subscriber/multicast_datagram.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"
#include "protocol/span_writer.h"

namespace skinstream::subscriber {
namespace {

size_t stride(size_t message_bytes, uint16_t count) { return (message_bytes + count - 1) / count; }

}  // namespace

uint16_t fragment_count(size_t message_bytes, bool authenticated, uint16_t max_fragments) {
  const size_t largest = authenticated ? kMaxAuthenticatedFragmentBytes : kMaxFragmentBytes;
  if (message_bytes == 0 || message_bytes > max_fragments * largest) return 0;
  return static_cast<uint16_t>((message_bytes + largest - 1) / largest);
}

size_t fragment_offset(size_t message_bytes, uint16_t count, uint16_t index) { return index * stride(message_bytes, count); }

size_t fragment_bytes(size_t message_bytes, uint16_t count, uint16_t index) {
  const size_t start = fragment_offset(message_bytes, count, index);
  return start >= message_bytes ? 0 : std::min(stride(message_bytes, count), message_bytes - start);
}

void encode_datagram_header(const DatagramHeader& h, std::span<unsigned char, kDatagramHeaderBytes> out) {
  SpanWriter w(out);
  w.put<uint32_t>(kDatagramMagic);
  w.put<uint16_t>(kDatagramVersion);
  w.put<uint16_t>((h.authenticated ? kDatagramAuthenticated : 0) |
                  (h.offer ? kDatagramOffer : 0));  // flags; the other bits reserved
  w.put<uint32_t>(h.stream_id);
  w.put<uint32_t>(h.model_id);
  w.put<uint32_t>(h.sequence);
  w.put<uint16_t>(h.index);
  w.put<uint16_t>(h.count);
  w.put<uint32_t>(h.message_bytes);
}

DatagramHeader decode_datagram_header(std::span<const unsigned char> datagram) {
  if (datagram.size() < kDatagramHeaderBytes)
    throw DecodeError("datagram of " + std::to_string(datagram.size()) + " bytes is shorter than its " +
                      std::to_string(kDatagramHeaderBytes) + "-byte header");
  if (datagram.size() > kMaxDatagramBytes)
    throw DecodeError("datagram of " + std::to_string(datagram.size()) + " bytes is over the " + std::to_string(kMaxDatagramBytes) + " allowed");
  ByteReader r(datagram);  // its size checked: no read below can fail
  if (r.get<uint32_t>("magic") != kDatagramMagic)
    throw DecodeError("bad magic (not a skinstream multicast datagram)");
  const uint16_t version = r.get<uint16_t>("version");
  if (version != kDatagramVersion) throw DecodeError("multicast datagram version " + std::to_string(version) + " (this side speaks 1)");
  const uint16_t flags = r.get<uint16_t>("flags");
  if (flags & ~(kDatagramAuthenticated | kDatagramOffer)) throw DecodeError("reserved header bits set");
  DatagramHeader h;
  h.authenticated = (flags & kDatagramAuthenticated) != 0;
  h.offer = (flags & kDatagramOffer) != 0;
  const uint16_t max_fragments = h.offer ? kMaxOfferFragments : kMaxFragments;
  const size_t largest = h.authenticated ? kMaxAuthenticatedFragmentBytes : kMaxFragmentBytes;
  const size_t trailer = h.authenticated ? kDatagramTrailerBytes : 0;
  h.stream_id = r.get<uint32_t>("stream id");
  h.model_id = r.get<uint32_t>("model id");
  h.sequence = r.get<uint32_t>("sequence");
  h.index = r.get<uint16_t>("fragment index");
  h.count = r.get<uint16_t>("fragment count");
  h.message_bytes = r.get<uint32_t>("message bytes");
  if (h.count == 0 || h.count > max_fragments)
    throw DecodeError("fragment count " + std::to_string(h.count) + " (1-" + std::to_string(max_fragments) +
                      ")");
  if (h.index >= h.count) throw DecodeError("fragment " + std::to_string(h.index) + " of " + std::to_string(h.count));
  if (h.message_bytes == 0 || stride(h.message_bytes, h.count) > largest ||
      fragment_bytes(h.message_bytes, h.count, static_cast<uint16_t>(h.count - 1)) == 0)
    throw DecodeError("a message of " + std::to_string(h.message_bytes) + " bytes cannot be cut into " + std::to_string(h.count) + " fragments");
  const size_t expected = fragment_bytes(h.message_bytes, h.count, h.index);
  if (datagram.size() - kDatagramHeaderBytes != expected + trailer)
    throw DecodeError("fragment " + std::to_string(h.index) + " of " + std::to_string(h.count) + " holds " +
                      std::to_string(datagram.size() - kDatagramHeaderBytes - std::min(trailer, datagram.size() - kDatagramHeaderBytes)) +
                      " bytes, not " + std::to_string(expected));
  return h;
}

uint32_t model_id_of(std::span<const unsigned char> model_payload) { return crc32(model_payload.data(), model_payload.size()); }

}  // namespace skinstream::subscriber
