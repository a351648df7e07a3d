#pragma once
// Turns a recorded Capture into Vicon DataStream frame packets, as a Vicon system would stream
// the same take: the labelled channels are the markers of one subject, channels named "" or "*N"
// are unlabelled reconstructions (trajectory id N; "" gets its channel index), a missing sample
// is left out of the frame (the SDK then reports the marker occluded).
//
// Frame numbers are those the SDK shows its users; the wire carries frame_number - 1 because
// the SDK adds one to FrameInfo. The timecode is derived from the frame number and the rate
// (Film 24 fps, PAL 25 or ATSC 30, whichever divides the rate, with subframes).

#include <cstdint>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/vicon_datastream.h"
#include "protocol/vicon_packet_writer.h"

namespace skinstream::vicon {

class CaptureFrameEncoder {
 public:
  static constexpr uint32_t kSubjectId = 1;

  // rate_hz: the rate announced in StreamInfo (0 = the capture's own rate).
  CaptureFrameEncoder(const Capture& capture, std::string subject_name, double rate_hz = 0.0);

  const StreamInfo& stream_info() const { return stream_info_; }
  const SubjectInfo& subject_info() const { return subject_info_; }
  double rate_hz() const { return rate_hz_; }
  int frame_count() const { return capture_.frame_count; }

  // The object types this stream offers (sent in ObjectEnums at connection).
  static ObjectEnums offered_types();

  // A packet of frame `index` of the capture, numbered `frame_number`. With include_static the
  // packet also carries StreamInfo and SubjectInfo (a client's first frame, every datagram).
  void encode_frame(int index, uint32_t frame_number, bool include_static, PacketWriter& writer);

  static Timecode timecode_for(uint32_t frame_number, double rate_hz);

 private:
  const Capture& capture_;
  double rate_hz_;
  StreamInfo stream_info_;
  SubjectInfo subject_info_;
  std::vector<int> labelled_channels_;    // marker id -> channel
  std::vector<int> unlabelled_channels_;
  std::vector<uint32_t> unlabelled_ids_;  // per unlabelled channel
  std::vector<LabeledRecon> labeled_;     // scratch, reused per frame
  std::vector<UnlabeledRecon> unlabeled_;
};

}  // namespace skinstream::vicon
