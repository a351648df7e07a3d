#pragma once
// Builds Vicon DataStream packets: the header, then one object per add(). The buffer is kept
// between packets, so a writer reused for every frame stops allocating once it has grown.

#include <cstdint>
#include <span>
#include <vector>

#include "protocol/vicon/vicon_datastream.h"

namespace skinstream::vicon {

class PacketWriter {
 public:
  PacketWriter() { begin(); }

  void begin();  // starts a new packet (keeps the buffer's capacity)

  void add(const ObjectEnums& object);
  void add(const RequestFrame& object);
  void add(const RequestNextFrame& object);
  void add(const Ping& object);
  void add(const StartMulticastSender& object);
  void add_stop_multicast_sender();
  void add(const Contents& object);
  void add(const Filter& object);
  void add(const StreamInfo& object);
  void add(const SubjectInfo& object);
  void add(const FrameInfo& object);
  void add(const Timecode& object);
  void add(std::span<const LabeledRecon> recons);
  void add(std::span<const UnlabeledRecon> recons);
  void add_raw(uint32_t type, std::span<const unsigned char> payload);  // any object, as is

  // The whole packet with its length filled in; valid until the next begin().
  std::span<const unsigned char> finish();

 private:
  template <typename T>
  void put(T value);
  void put_string(const std::string& s);
  size_t begin_object(uint32_t type);
  void end_object(size_t length_offset);

  std::vector<unsigned char> bytes_;
};

// One packet holding the given objects, e.g. encode_packet(RequestFrame{true}).
template <typename... Objects>
std::vector<unsigned char> encode_packet(const Objects&... objects) {
  PacketWriter writer;
  (writer.add(objects), ...);
  const auto packet = writer.finish();
  return {packet.begin(), packet.end()};
}

}  // namespace skinstream::vicon
