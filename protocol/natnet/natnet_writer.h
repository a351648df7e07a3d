#pragma once
// Writes NatNet messages (protocol/natnet/natnet.h) in a chosen layout (3.x, 4.0, 4.1). Frames are
// written into a caller's buffer that keeps its capacity, so a writer reused for every frame stops
// allocating once it has grown. A message over the u16 byte count's reach is refused
// (std::length_error): the caller streams fewer markers or splits the take.

#include <string_view>
#include <vector>

#include "protocol/natnet/natnet.h"

namespace skinstream::natnet {

using ByteVector = std::vector<unsigned char>;

// An empty request (RequestModelDef, KeepAlive, ...).
ByteVector encode_empty(uint16_t message_id);
// CONNECT as a client announces itself: char name[256], u8 version[4], u8 NatNet version[4].
ByteVector encode_connect(std::string_view client_name, Version wanted);
ByteVector encode_server_info(const ServerInfo& info);
ByteVector encode_model_definitions(const ModelDefinitions& definitions, Version version);
// Request / Response / MessageString text with its NUL.
ByteVector encode_text(uint16_t message_id, std::string_view text);

void encode_frame(const FrameOfData& frame, Version version, ByteVector& out);

}  // namespace skinstream::natnet
