#pragma once
// What the multicast offer carries (docs/subscriber-protocol.md, "The offer"): exactly what a
// version 2 subscriber of the parameter encoding that reads Packed messages is sent as it joins,
// headers included: the Packed message holding its MeshInfo, then the one holding the Model.
// The datagrams that carry it: protocol/subscriber/multicast_datagram.h; put back together by
// protocol/subscriber/offer_reassembler.h. No sockets here.

#include <cstdint>
#include <span>
#include <vector>

#include "protocol/subscriber/packed_message.h"

namespace skinstream::subscriber {

std::vector<unsigned char> encode_offer(std::span<const unsigned char> packed_mesh_info_message,
                                        std::span<const unsigned char> packed_model_message);

struct OfferContent {
  Unpacked mesh_info;  // its payload as a plain MeshInfo's (decode_mesh_info, version 2)
  Unpacked model;      // its payload as a plain Model's (decode_model)
};
// The offer's two messages unpacked. DecodeError naming what is wrong: not two version 2 Packed
// messages filling the offer, the MeshInfo's then the Model's; a Packed payload that does not
// unpack (decode_packed); or a Model whose id (model_id_of) is not `model_id`, the id its
// datagrams and the frames carry.
OfferContent decode_offer(std::span<const unsigned char> offer, uint32_t model_id);

}  // namespace skinstream::subscriber
