#pragma once
// Turns recorded captures into what QTM streams for the same takes: the 3D parameters (every
// subject's labelled markers, prefixed by the subject, protocol/qtm/qtm_labels.h) and one Data packet
// per frame with a 3D component (a position per label, NaN when missing) and a 3D no labels
// component (the present unlabelled points; the second subject's ids are offset by 1,000,000,
// the third's by 2,000,000, so they stay unique).
//
// Stream index k (counting on across loops) is frame number first_frame + k of the first
// recording, at timestamp k / rate in microseconds; its positions are frame k modulo the stream
// length.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "protocol/files/replay_subject.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "protocol/qtm/qtm_parameters.h"

namespace skinstream::qtm {

class CaptureEncoder {
 public:
  static constexpr uint32_t kUnlabelledIdStride = 1'000'000;

  // rate_hz: the announced rate (0: the first capture's).
  CaptureEncoder(std::vector<ReplaySubject> subjects, double rate_hz = 0.0);

  const Parameters& parameters() const { return parameters_; }
  double rate_hz() const { return rate_hz_; }
  int frame_count() const { return frame_count_; }
  uint32_t frame_number(uint64_t stream_index) const;

  // The Data packet of stream index k with the 3D and/or the 3D no labels component (allocates
  // nothing once the writer has grown).
  std::span<const unsigned char> encode_frame(uint64_t stream_index, DataPacketWriter& writer,
                                              bool labelled = true, bool unlabelled = true);

 private:
  std::vector<ReplaySubject> subjects_;
  std::vector<ReplayChannels> channels_;
  double rate_hz_;
  int frame_count_;
  Parameters parameters_;
  std::vector<std::array<float, 3>> labelled_;  // scratch, reused per frame
  std::vector<UnlabelledMarker> unlabelled_;
};

}  // namespace skinstream::qtm
