#include "protocol/natnet/natnet_capture_encoder.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "protocol/vicon/vicon_capture_encoder.h"

namespace skinstream::natnet {
namespace {

Point metres(const Vec3& mm) {
  return {static_cast<float>(mm.x() / 1000.0), static_cast<float>(mm.y() / 1000.0),
          static_cast<float>(mm.z() / 1000.0)};
}

}  // namespace

CaptureEncoder::CaptureEncoder(std::vector<ReplaySubject> subjects, double rate_hz)
    : subjects_(std::move(subjects)),
      rate_hz_(rate_hz > 0.0 ? rate_hz : (subjects_.empty() ? 0.0 : subjects_[0].capture->rate_hz)),
      frame_count_(replay_frame_count(subjects_)) {
  size_t labelled = 0, unlabelled = 0;
  for (const ReplaySubject& subject : subjects_) {
    channels_.push_back(replay_channels(*subject.capture));
    MarkerSetDescription& set = definitions_.marker_sets.emplace_back();
    set.name = subject.name;
    for (int channel : channels_.back().labelled) set.markers.push_back(subject.capture->labels[static_cast<size_t>(channel)]);
    labelled += set.markers.size();
    unlabelled += channels_.back().unlabelled.size();
    MarkerSetData& data = frame_.marker_sets.emplace_back();
    data.name = subject.name;
    data.positions.resize(set.markers.size());
  }
  frame_.marker_set_count = frame_.marker_sets.size();
  frame_.other_markers.reserve(unlabelled);
  frame_.labelled_markers.reserve(labelled + unlabelled);
}

void CaptureEncoder::set_clock(const Clock& clock) {
  clock_ = clock;
  random_.seed(clock.seed);
}

uint32_t CaptureEncoder::frame_number(uint64_t stream_index) const {
  const int first = subjects_.empty() ? 1 : subjects_[0].capture->first_frame;
  return static_cast<uint32_t>(static_cast<int64_t>(first) + static_cast<int64_t>(stream_index));
}

const FrameOfData& CaptureEncoder::frame(uint64_t stream_index) {
  const int index = frame_count_ > 0 ? static_cast<int>(stream_index % static_cast<uint64_t>(frame_count_)) : 0;
  const uint32_t frame_number = this->frame_number(stream_index);
  frame_.frame_number = static_cast<int32_t>(frame_number);
  frame_.other_markers.clear();
  frame_.labelled_markers.clear();
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (size_t s = 0; s < subjects_.size(); ++s) {
    const Capture& capture = *subjects_[s].capture;
    const ReplayChannels& channels = channels_[s];
    for (size_t m = 0; m < channels.labelled.size(); ++m) {
      const Vec3 p = replay_sample(capture, index, channels.labelled[m]);
      frame_.marker_sets[s].positions[m] = is_present(p) ? metres(p) : Point{kNaN, kNaN, kNaN};
      if (!is_present(p)) continue;  // Motive leaves an unmeasured marker out of this list
      LabelledMarker& lm = frame_.labelled_markers.emplace_back();
      lm.id = static_cast<uint32_t>(s + 1) << 16 | static_cast<uint32_t>(m + 1);
      lm.position = metres(p);
      lm.size = kMarkerSizeMetres;
      lm.params = kMarkerHasModel;
      lm.residual = 0.0f;
    }
  }
  for (size_t s = 0; s < subjects_.size(); ++s) {
    const ReplayChannels& channels = channels_[s];
    for (size_t u = 0; u < channels.unlabelled.size(); ++u) {
      const Vec3 p = replay_sample(*subjects_[s].capture, index, channels.unlabelled[u]);
      if (!is_present(p)) continue;
      frame_.other_markers.push_back(metres(p));
      LabelledMarker& lm = frame_.labelled_markers.emplace_back();
      lm.id = (channels.unlabelled_ids[u] + static_cast<uint32_t>(s) * kUnlabelledIdStride) & 0xFFFF;
      lm.position = metres(p);
      lm.size = kMarkerSizeMetres;
      lm.params = kMarkerUnlabelled;
    }
  }
  const vicon::Timecode tc = vicon::CaptureFrameEncoder::timecode_for(frame_number, rate_hz_);
  frame_.timecode = join_timecode({tc.hours, tc.minutes, tc.seconds, tc.frames});
  frame_.timecode_subframe = tc.subframes;
  frame_.timestamp_s = rate_hz_ > 0.0 ? static_cast<double>(stream_index) / rate_hz_ : 0.0;
  if (clock_.jitter_s > 0.0)
    frame_.timestamp_s = std::max(0.0, frame_.timestamp_s + std::uniform_real_distribution<double>(-clock_.jitter_s, clock_.jitter_s)(random_));
  if (clock_.ticks_per_second > 0.0)
    frame_.timestamp_s = static_cast<double>(std::llround(frame_.timestamp_s * clock_.ticks_per_second)) / clock_.ticks_per_second;
  const auto ticks = static_cast<uint64_t>(std::llround(frame_.timestamp_s * 1e9));  // 1 GHz clock
  frame_.stamp_mid_exposure = frame_.stamp_data_received = ticks;
  frame_.stamp_transmit = ticks + static_cast<uint64_t>(std::llround(clock_.latency_s * 1e9));
  frame_.precise_seconds = static_cast<uint32_t>(frame_.timestamp_s);
  frame_.precise_fraction = static_cast<uint32_t>((frame_.timestamp_s - std::floor(frame_.timestamp_s)) * 4294967296.0);
  frame_.params = stream_index >= recording_first_ && stream_index < recording_end_ ? kFrameRecording : 0;
  return frame_;
}

void CaptureEncoder::encode(uint64_t stream_index, Version version, ByteVector& out) {
  encode_frame(frame(stream_index), version, out);
}

}  // namespace skinstream::natnet
