#pragma once
// Turns recorded Captures into Vicon DataStream frame packets, as a Vicon system would stream
// the same takes: each recording is one subject (subject ids 1, 2, ... in the order given), its
// labelled channels that subject's markers; channels named "" or "*N" are unlabelled
// reconstructions (trajectory id N, "" its channel index); a missing sample is left out of the
// frame (the SDK then reports the marker occluded). Trajectory ids of the second recording on
// have the recording's index << 24 added, so that two recordings' ids never meet.
//
// Several recordings play together, frame k of the stream holding frame k of each (with loop,
// each starts again at its own end). A subject is listed (in SubjectInfo, with its markers) only
// in frames where its recording has a labelled marker: an actor off the stage, or a recording
// that has ended, leaves the subject list, as when an operator disables a subject, and comes back
// with its markers. listed() says which subjects a frame lists, so a server can send SubjectInfo
// again whenever that changes.
//
// Frame numbers are those the SDK shows its users; the wire carries frame_number - 1 because
// the SDK adds one to FrameInfo. The timecode is derived from the frame number and the rate
// (Film 24 fps, PAL 25 or ATSC 30, whichever divides the rate, with subframes).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/files/replay_subject.h"
#include "protocol/vicon/vicon_datastream.h"
#include "protocol/vicon/vicon_packet_writer.h"

namespace skinstream::vicon {

class CaptureFrameEncoder {
 public:
  static constexpr size_t kMaxSubjects = 64;  // listed() is a bit per subject

  // rate_hz: the rate announced in StreamInfo (0 = the recordings' own rate). Throws
  // std::invalid_argument for no subject, more than kMaxSubjects, or, without rate_hz,
  // recordings whose rates differ (one stream has one rate).
  CaptureFrameEncoder(std::span<const ReplaySubject> subjects, double rate_hz = 0.0, bool loop = false);
  CaptureFrameEncoder(const Capture& capture, std::string subject_name, double rate_hz = 0.0)
      : CaptureFrameEncoder(std::vector<ReplaySubject>{{std::move(subject_name), &capture}}, rate_hz) {}

  const StreamInfo& stream_info() const { return stream_info_; }
  double rate_hz() const { return rate_hz_; }
  int frame_count() const { return frame_count_; }  // the longest recording's
  int first_frame() const { return subjects_.front().capture->first_frame; }

  // The object types this stream offers (sent in ObjectEnums at connection).
  static ObjectEnums offered_types();

  // Bit s: subject s is listed in stream frame `sequence`.
  uint64_t listed(uint64_t sequence) const;

  // A packet of stream frame `sequence` (frame `sequence` of each recording; with loop, each
  // recording's own frame count wraps it), numbered `frame_number`. With include_static the
  // packet also carries StreamInfo and the listed subjects' SubjectInfo (a client's first frame,
  // a change of the listed subjects, every datagram).
  void encode_frame(uint64_t sequence, uint32_t frame_number, bool include_static, PacketWriter& writer);

  static Timecode timecode_for(uint32_t frame_number, double rate_hz);

 private:
  struct Subject {
    const Capture* capture = nullptr;
    SubjectInfo info;
    ReplayChannels channels;  // labelled: marker id -> channel
    uint32_t id_base = 0;     // added to its trajectory ids
  };
  int index_of(const Subject& subject, uint64_t sequence) const;  // -1: the recording has ended
  bool on_stage(const Subject& subject, int index) const;

  std::vector<Subject> subjects_;
  double rate_hz_;
  bool loop_;
  int frame_count_ = 0;
  StreamInfo stream_info_;
  std::vector<LabeledRecon> labeled_;     // scratch, reused per frame
  std::vector<UnlabeledRecon> unlabeled_;
};

}  // namespace skinstream::vicon
