#include "protocol/files/replay_subject.h"

#include <algorithm>
#include <charconv>

namespace skinstream {

ReplayChannels replay_channels(const Capture& capture) {
  ReplayChannels channels;
  for (int channel = 0; channel < capture.point_count(); ++channel) {
    if (capture.is_labelled(channel)) {
      channels.labelled.push_back(channel);
      continue;
    }
    const std::string& label = capture.labels[static_cast<size_t>(channel)];
    uint32_t id = static_cast<uint32_t>(channel);
    if (label.size() > 1) std::from_chars(label.data() + 1, label.data() + label.size(), id);  // "*N": digits only
    channels.unlabelled.push_back(channel);
    channels.unlabelled_ids.push_back(id);
  }
  return channels;
}

int replay_frame_count(std::span<const ReplaySubject> subjects) {
  int frames = 0;
  for (const ReplaySubject& s : subjects) frames = std::max(frames, s.capture->frame_count);
  return frames;
}

Vec3 replay_sample(const Capture& capture, int index, int channel) {
  return index < capture.frame_count ? capture.at(index, channel) : missing_point();
}

}  // namespace skinstream
