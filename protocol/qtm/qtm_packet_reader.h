#pragma once
// Reads QTM RT packets (protocol/qtm/qtm_rt.h): every read is bounds-checked, and a packet whose
// sizes, counts or component layout disagree is refused with a one-line reason, never read past
// its end. Decoding a Data packet into the same DataFrame again allocates nothing once its
// vectors have grown, so a client can decode every frame.

#include <string>

#include "protocol/qtm/qtm_rt.h"

namespace skinstream::qtm {

// The packet's size and type, checked against the bytes given: the size field must equal
// packet.size(), be at least the header and at most kMaxPacketBytes.
bool read_header(Bytes packet, uint32_t& out_type, std::string& out_error);

// A Command, Error or XML packet's text, up to its NUL (or the end, when a client sent none).
bool decode_text(Bytes packet, std::string& out_text, std::string& out_error);
bool decode_event(Bytes packet, Event& out_event, std::string& out_error);
bool decode_data(Bytes packet, DataFrame& out_frame, std::string& out_error);

// Any packet, for control traffic, tests and fuzzing (allocates).
struct Packet {
  uint32_t type = 0;
  std::string text;  // Command, Error, XML
  Event event = Event::Connected;
  DataFrame data;
};
bool decode_packet(Bytes packet, Packet& out, std::string& out_error);

}  // namespace skinstream::qtm
