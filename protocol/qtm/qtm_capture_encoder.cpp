#include "protocol/qtm/qtm_capture_encoder.h"

#include <cmath>
#include <limits>

#include "protocol/qtm/qtm_labels.h"

namespace skinstream::qtm {

CaptureEncoder::CaptureEncoder(std::vector<ReplaySubject> subjects, double rate_hz)
    : subjects_(std::move(subjects)),
      rate_hz_(rate_hz > 0.0 ? rate_hz : (subjects_.empty() ? 0.0 : subjects_[0].capture->rate_hz)),
      frame_count_(replay_frame_count(subjects_)) {
  parameters_.frequency_hz = rate_hz_;
  parameters_.capture_time_s = rate_hz_ > 0.0 ? frame_count_ / rate_hz_ : 0.0;
  parameters_.has_3d = true;
  size_t unlabelled = 0;
  for (const ReplaySubject& subject : subjects_) {
    channels_.push_back(replay_channels(*subject.capture));
    for (int channel : channels_.back().labelled)
      parameters_.labels.push_back(prefixed_label(subject.name, subject.capture->labels[static_cast<size_t>(channel)]));
    unlabelled += channels_.back().unlabelled.size();
  }
  labelled_.reserve(parameters_.labels.size());
  unlabelled_.reserve(unlabelled);
}

uint32_t CaptureEncoder::frame_number(uint64_t stream_index) const {
  const int first = subjects_.empty() ? 1 : subjects_[0].capture->first_frame;
  return static_cast<uint32_t>(static_cast<int64_t>(first) + static_cast<int64_t>(stream_index));
}

std::span<const unsigned char> CaptureEncoder::encode_frame(uint64_t stream_index, DataPacketWriter& writer,
                                                            bool labelled, bool unlabelled) {
  const int index = frame_count_ > 0 ? static_cast<int>(stream_index % static_cast<uint64_t>(frame_count_)) : 0;
  const auto timestamp_us =
      rate_hz_ > 0.0 ? static_cast<int64_t>(std::llround(static_cast<double>(stream_index) * 1e6 / rate_hz_)) : 0;
  writer.begin(timestamp_us, frame_number(stream_index));
  labelled_.clear();
  unlabelled_.clear();
  for (size_t s = 0; s < subjects_.size(); ++s) {
    const Capture& capture = *subjects_[s].capture;
    const ReplayChannels& channels = channels_[s];
    for (int channel : channels.labelled) {
      const Vec3 p = replay_sample(capture, index, channel);
      constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
      labelled_.push_back(is_present(p) ? std::array<float, 3>{static_cast<float>(p.x()), static_cast<float>(p.y()),
                                                               static_cast<float>(p.z())}
                                        : std::array<float, 3>{kNaN, kNaN, kNaN});
    }
    for (size_t u = 0; u < channels.unlabelled.size(); ++u) {
      const Vec3 p = replay_sample(capture, index, channels.unlabelled[u]);
      if (!is_present(p)) continue;
      UnlabelledMarker& m = unlabelled_.emplace_back();
      m.position = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
      m.id = channels.unlabelled_ids[u] + static_cast<uint32_t>(s) * kUnlabelledIdStride;
    }
  }
  if (labelled) writer.add_labelled(labelled_);
  if (unlabelled) writer.add_unlabelled(unlabelled_);
  return writer.finish();
}

}  // namespace skinstream::qtm
