#include "protocol/subscriber/offer_content.h"

#include <cstdio>
#include <string>

#include "protocol/subscriber/multicast_datagram.h"

namespace skinstream::subscriber {

std::vector<unsigned char> encode_offer(std::span<const unsigned char> packed_mesh_info_message,
                                        std::span<const unsigned char> packed_model_message) {
  std::vector<unsigned char> offer;
  offer.reserve(packed_mesh_info_message.size() + packed_model_message.size());
  offer.insert(offer.end(), packed_mesh_info_message.begin(), packed_mesh_info_message.end());
  offer.insert(offer.end(), packed_model_message.begin(), packed_model_message.end());
  return offer;
}

OfferContent decode_offer(std::span<const unsigned char> offer, uint32_t model_id) {
  OfferContent content;
  size_t at = 0;
  for (const MessageType expected : {MessageType::MeshInfo, MessageType::Model}) {
    const MessageHeader header = decode_header(offer.subspan(at));
    if (header.type != MessageType::Packed || header.version != kVersion2)
      throw DecodeError(std::string("the offer holds a ") + to_string(header.type) + " message of version " +
                        std::to_string(header.version) + " where a version 2 Packed " + to_string(expected) +
                        " belongs");
    if (header.payload_bytes > offer.size() - at - kHeaderBytes)
      throw DecodeError("the offer's " + std::string(to_string(expected)) + " message is cut short");
    Unpacked unpacked = decode_packed(offer.subspan(at + kHeaderBytes, header.payload_bytes));
    if (unpacked.type != expected)
      throw DecodeError(std::string("the offer holds a packed ") + to_string(unpacked.type) + " where its " +
                        to_string(expected) + " belongs");
    (expected == MessageType::MeshInfo ? content.mesh_info : content.model) = std::move(unpacked);
    at += kHeaderBytes + header.payload_bytes;
  }
  if (at != offer.size())
    throw DecodeError(std::to_string(offer.size() - at) + " bytes after the offer's Model");
  if (const uint32_t id = model_id_of(content.model.payload); id != model_id) {
    char text[112];
    std::snprintf(text, sizeof text, "the offer's Model has id %08x, and its datagrams say %08x", id,
                  model_id);
    throw DecodeError(text);
  }
  return content;
}

}  // namespace skinstream::subscriber
