#pragma once
// Reads Vicon DataStream packets: splits a whole packet into its objects, then decodes each
// object's payload. Every read is bounds-checked; a malformed packet yields false and a one-line
// reason, never an out-of-bounds read. Decoding into a reused vector allocates nothing once the
// vector has grown (LabeledRecons, UnlabeledRecons), so a client can decode every frame.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/vicon/vicon_datastream.h"

namespace skinstream::vicon {

using Bytes = std::span<const unsigned char>;

struct ObjectView {
  uint32_t type = 0;
  Bytes payload;
};

// Checks the header (magic, length = bytes that follow, <= kMaxPacketLength), that the objects
// tile the payload exactly and that there are at most limits.max_subjects SubjectInfo objects;
// out_objects is cleared and refilled (its capacity is reused).
bool split_objects(Bytes packet, std::vector<ObjectView>& out_objects, std::string& out_error,
                   const DescriptionLimits& limits = {});

// One object payload each. Bytes after the fields an object defines are ignored, as the SDK does
// (newer servers may append fields); missing bytes and implausible counts are errors, and so are
// a StreamInfo period outside kMinFramePeriodTicks..kMaxFramePeriodTicks and a SubjectInfo
// beyond `limits`.
bool decode(Bytes payload, ObjectEnums& out, std::string& out_error);
bool decode(Bytes payload, RequestFrame& out, std::string& out_error);
bool decode(Bytes payload, RequestNextFrame& out, std::string& out_error);
bool decode(Bytes payload, Ping& out, std::string& out_error);
bool decode(Bytes payload, StartMulticastSender& out, std::string& out_error);
bool decode(Bytes payload, Contents& out, std::string& out_error);
bool decode(Bytes payload, Filter& out, std::string& out_error);
bool decode(Bytes payload, StreamInfo& out, std::string& out_error);
bool decode(Bytes payload, SubjectInfo& out, std::string& out_error, const DescriptionLimits& limits = {});
bool decode(Bytes payload, FrameInfo& out, std::string& out_error);
bool decode(Bytes payload, Timecode& out, std::string& out_error);
bool decode(Bytes payload, std::vector<LabeledRecon>& out, std::string& out_error);
bool decode(Bytes payload, std::vector<UnlabeledRecon>& out, std::string& out_error);

// A whole packet decoded into values, for control traffic and tests (allocates; the per-frame
// client path uses split_objects + decode instead). Objects of types not listed here are skipped
// and their type ids collected in unknown_types.
struct DecodedPacket {
  std::vector<uint32_t> object_types;  // in packet order
  ObjectEnums object_enums;
  RequestFrame request_frame;
  RequestNextFrame request_next_frame;
  Ping ping;
  StartMulticastSender start_multicast;
  Contents contents;
  Filter filter;
  StreamInfo stream_info;
  std::vector<SubjectInfo> subjects;
  FrameInfo frame_info;
  Timecode timecode;
  std::vector<LabeledRecon> labeled;
  std::vector<UnlabeledRecon> unlabeled;
  std::vector<uint32_t> unknown_types;

  bool has(uint32_t type) const;
};

bool decode_packet(Bytes packet, DecodedPacket& out, std::string& out_error, const DescriptionLimits& limits = {});

}  // namespace skinstream::vicon
