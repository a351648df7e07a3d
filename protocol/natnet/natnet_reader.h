#pragma once
// Reads NatNet messages (protocol/natnet/natnet.h). Every read is bounds-checked; counts that cannot
// fit in what is left, 4.1 section byte counts that disagree with their sections, names without
// their NUL and unknown layouts are refused with a one-line reason, never read past the end.
// Decoding a frame into the same FrameOfData again allocates nothing once it has grown.

#include <string>

#include "protocol/natnet/natnet.h"

namespace skinstream::natnet {

// A datagram's message id and payload (the byte count must fit in the datagram; bytes after it
// are ignored: clients send a NUL after an empty request).
bool read_message(Bytes datagram, uint16_t& out_id, Bytes& out_payload, std::string& out_error);

bool decode_server_info(Bytes payload, ServerInfo& out, std::string& out_error);
bool decode_model_definitions(Bytes payload, Version version, ModelDefinitions& out, std::string& out_error);
bool decode_frame(Bytes payload, Version version, FrameOfData& out, std::string& out_error);

// Any datagram, for tests and fuzzing: the message decoded by its id (allocates).
struct Message {
  uint16_t id = 0;
  ServerInfo server_info;
  ModelDefinitions model_definitions;
  FrameOfData frame;
  std::string text;  // Request, Response and MessageString text
};
bool decode_message(Bytes datagram, Version version, Message& out, std::string& out_error);

}  // namespace skinstream::natnet
