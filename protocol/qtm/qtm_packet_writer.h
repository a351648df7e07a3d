#pragma once
// Builds QTM RT packets (protocol/qtm/qtm_rt.h), little-endian. Text packets carry their NUL, as QTM
// sends them. The data writer keeps its buffer between frames, so a writer reused for every
// frame stops allocating once it has grown.

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "protocol/qtm/qtm_rt.h"

namespace skinstream::qtm {

std::vector<unsigned char> encode_text(PacketType type, std::string_view text);  // Command, Error, XML
std::vector<unsigned char> encode_event(Event event);
std::vector<unsigned char> encode_no_more_data();

class DataPacketWriter {
 public:
  void begin(int64_t timestamp_us, uint32_t frame_number);  // keeps the buffer's capacity
  // 3D: one position per label, NaN for the labels not measured this frame.
  void add_labelled(std::span<const std::array<float, 3>> positions);
  // 3D no labels: positions with their trajectory ids.
  void add_unlabelled(std::span<const UnlabelledMarker> markers);
  // The whole packet with its sizes filled in; valid until the next begin().
  std::span<const unsigned char> finish();

 private:
  size_t begin_component(uint32_t type, uint32_t count);
  void end_component(size_t start);
  template <typename T>
  void put(T value);

  std::vector<unsigned char> bytes_;
  uint32_t components_ = 0;
};

}  // namespace skinstream::qtm
