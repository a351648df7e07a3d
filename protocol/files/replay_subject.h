#pragma once
// Recordings streamed together as several subjects (skinstream-replay RECORDING...): each keeps
// its own labels; the stream lasts as long as the longest, and a shorter recording's markers are
// occluded after its last frame. Shared by the QTM RT and NatNet encoders.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct ReplaySubject {
  std::string name;
  const Capture* capture = nullptr;  // outlives every encoder made from it
};

// A capture's channels split as a capture system streams them: labelled markers (by name) and
// unlabelled points ("" or "*N", id N; "" gets its channel index).
struct ReplayChannels {
  std::vector<int> labelled;
  std::vector<int> unlabelled;
  std::vector<uint32_t> unlabelled_ids;  // one per unlabelled channel
};
ReplayChannels replay_channels(const Capture& capture);

int replay_frame_count(std::span<const ReplaySubject> subjects);  // the longest
// The sample of `channel` at stream index `index` (NaN once the recording has ended).
Vec3 replay_sample(const Capture& capture, int index, int channel);

}  // namespace skinstream
