#include "protocol/vicon/vicon_datastream.h"

#include <cmath>

namespace skinstream::vicon {

const char* object_type_name(uint32_t type) {
  switch (type) {
    case object_type::StreamInfo: return "StreamInfo";
    case object_type::SubjectInfo: return "SubjectInfo";
    case object_type::FrameInfo: return "FrameInfo";
    case object_type::LabeledRecons: return "LabeledRecons";
    case object_type::UnlabeledRecons: return "UnlabeledRecons";
    case object_type::Timecode: return "Timecode";
    case object_type::ApexHaptics: return "ApexHaptics";
    case object_type::Ping: return "Ping";
    case object_type::ObjectEnums: return "ObjectEnums";
    case object_type::RequestFrame: return "RequestFrame";
    case object_type::KeepAlive: return "KeepAlive";
    case object_type::Contents: return "Contents";
    case object_type::StartMulticastSender: return "StartMulticastSender";
    case object_type::StopMulticastSender: return "StopMulticastSender";
    case object_type::Filter: return "Filter";
    case object_type::RequestNextFrame: return "RequestNextFrame";
  }
  return "unknown";
}

int64_t frame_period_ticks(double rate_hz) {
  if (!(rate_hz > 0.0)) return 0;
  return static_cast<int64_t>(std::llround(static_cast<double>(kTicksPerSecond) / rate_hz));
}

double rate_from_period(int64_t frame_period_ticks) {
  if (frame_period_ticks <= 0) return 0.0;
  return static_cast<double>(kTicksPerSecond) / static_cast<double>(frame_period_ticks);
}

}  // namespace skinstream::vicon
