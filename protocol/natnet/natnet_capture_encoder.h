#pragma once
// Turns recorded captures into what Motive streams for the same takes over NatNet: one marker
// set per recording (named after it, its labelled markers in channel order) in the model
// definitions, and per frame
//   - the marker sets' positions in metres (NaN for a marker not measured this frame),
//   - the unlabelled points ("" or "*N") as other markers,
//   - the labelled markers list as Motive 3 fills it: every measured marker of set s (model id
//     s + 1, member id = its index + 1, params "has model"), then the unlabelled points (model
//     id 0, their own id, params "unlabelled"; the second
//     recording's ids offset by 10,000, all modulo 65,536: the member id has 16 bits),
//   - SMPTE timecode from the frame number (as the Vicon replay derives it), timestamp k / rate,
//     or, with set_clock(), k / rate as a real capture clock gives it: moved by a random offset
//     of up to +-jitter and quantised to the ticks of a clock of a given frequency.
// Stream index k is frame number first_frame + k of the first recording.

#include <cstdint>
#include <random>
#include <vector>

#include "protocol/files/replay_subject.h"
#include "protocol/natnet/natnet.h"
#include "protocol/natnet/natnet_writer.h"

namespace skinstream::natnet {

class CaptureEncoder {
 public:
  static constexpr uint32_t kUnlabelledIdStride = 10'000;  // ids are 16 bits for model 0
  static constexpr float kMarkerSizeMetres = 0.014f;

  CaptureEncoder(std::vector<ReplaySubject> subjects, double rate_hz = 0.0);

  // The timestamps as an imperfect capture clock stamps them (the default is exact).
  struct Clock {
    double jitter_s = 0.0;       // each timestamp moved by a uniform random offset in [-jitter, +jitter]
    double ticks_per_second = 0.0;  // > 0: then rounded to the ticks of a clock of this frequency
    uint32_t seed = 1;
    double latency_s =
        0.0;  // the transmit stamp this long after the mid-exposure stamp (the system's own latency)
  };
  void set_clock(const Clock& clock);

  const ModelDefinitions& model_definitions() const { return definitions_; }
  double rate_hz() const { return rate_hz_; }
  int frame_count() const { return frame_count_; }

  // Stream index k's frame number: the first recording's first frame + k.
  uint32_t frame_number(uint64_t stream_index) const;
  // The frame of stream index k, then its bytes in `version`'s layout (no allocation once warm).
  const FrameOfData& frame(uint64_t stream_index);
  void encode(uint64_t stream_index, Version version, ByteVector& out);
  // Frames of stream indices [first, end) say that Motive records (frame params bit 0), as a
  // take recorded on the capture system during the stream would.
  void set_recording_frames(uint64_t first, uint64_t end) {
    recording_first_ = first;
    recording_end_ = end;
  }

 private:
  std::vector<ReplaySubject> subjects_;
  std::vector<ReplayChannels> channels_;
  double rate_hz_;
  int frame_count_;
  ModelDefinitions definitions_;
  FrameOfData frame_;
  Clock clock_;
  std::mt19937 random_{1};
  uint64_t recording_first_ = 0, recording_end_ = 0;
};

}  // namespace skinstream::natnet
