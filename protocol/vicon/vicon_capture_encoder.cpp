#include "protocol/vicon/vicon_capture_encoder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skinstream::vicon {
namespace {

constexpr double kMarkerRadiusMm = 7.0;  // a 14 mm marker; the SDK does not use it for positions

}  // namespace

CaptureFrameEncoder::CaptureFrameEncoder(std::span<const ReplaySubject> subjects, double rate_hz, bool loop) : loop_(loop) {
  if (subjects.empty()) throw std::invalid_argument("no recording to stream");
  if (subjects.size() > kMaxSubjects) throw std::invalid_argument("at most " + std::to_string(kMaxSubjects) + " recordings");
  const double own_rate = subjects.front().capture->rate_hz;
  rate_hz_ = rate_hz > 0.0 ? rate_hz : own_rate;
  stream_info_.frame_period_ticks = frame_period_ticks(rate_hz_);
  for (size_t s = 0; s < subjects.size(); ++s) {
    const Capture& capture = *subjects[s].capture;
    if (!(rate_hz > 0.0) && std::abs(capture.rate_hz - own_rate) > 1e-6)
      throw std::invalid_argument("recordings at different rates (" + subjects.front().name + " " + std::to_string(own_rate) + " Hz, " +
                                  subjects[s].name + " " + std::to_string(capture.rate_hz) + " Hz): one stream has one rate");
    Subject& subject = subjects_.emplace_back();
    subject.capture = &capture;
    subject.info.subject_id = static_cast<uint32_t>(s + 1);
    subject.info.name = subjects[s].name;
    subject.channels = replay_channels(capture);
    subject.id_base = static_cast<uint32_t>(s) << 24;
    for (size_t marker = 0; marker < subject.channels.labelled.size(); ++marker)
      subject.info.markers.push_back({static_cast<uint32_t>(marker), capture.labels[static_cast<size_t>(subject.channels.labelled[marker])]});
    labeled_.reserve(labeled_.capacity() + subject.channels.labelled.size());
    unlabeled_.reserve(unlabeled_.capacity() + subject.channels.unlabelled.size());
  }
  frame_count_ = replay_frame_count(subjects);
}

ObjectEnums CaptureFrameEncoder::offered_types() {
  return {{object_type::StreamInfo, object_type::SubjectInfo, object_type::FrameInfo, object_type::LabeledRecons,
           object_type::UnlabeledRecons, object_type::Timecode, object_type::Ping, object_type::Contents}};
}

int CaptureFrameEncoder::index_of(const Subject& subject, uint64_t sequence) const {
  const auto count = static_cast<uint64_t>(subject.capture->frame_count);
  if (count == 0) return -1;
  if (loop_) return static_cast<int>(sequence % count);
  return sequence < count ? static_cast<int>(sequence) : -1;
}

bool CaptureFrameEncoder::on_stage(const Subject& subject, int index) const {
  if (index < 0) return false;
  for (int channel : subject.channels.labelled)
    if (subject.capture->present(index, channel)) return true;
  return false;
}

uint64_t CaptureFrameEncoder::listed(uint64_t sequence) const {
  uint64_t bits = 0;
  for (size_t s = 0; s < subjects_.size(); ++s)
    if (on_stage(subjects_[s], index_of(subjects_[s], sequence))) bits |= uint64_t{1} << s;
  return bits;
}

void CaptureFrameEncoder::encode_frame(uint64_t sequence, uint32_t frame_number, bool include_static, PacketWriter& writer) {
  const uint64_t listed_now = listed(sequence);
  writer.begin();
  if (include_static) {
    writer.add(stream_info_);
    for (size_t s = 0; s < subjects_.size(); ++s)
      if ((listed_now >> s) & 1u) writer.add(subjects_[s].info);
  }
  writer.add(FrameInfo{frame_number - 1});  // the SDK reports FrameInfo + 1
  writer.add(timecode_for(frame_number, rate_hz_));
  labeled_.clear();
  unlabeled_.clear();
  for (size_t s = 0; s < subjects_.size(); ++s) {
    const Subject& subject = subjects_[s];
    const int index = index_of(subject, sequence);
    if (index < 0) continue;
    const Capture& capture = *subject.capture;
    const bool on_stage_now = (listed_now >> s) & 1u;  // else it has no labelled marker to send
    for (size_t marker = 0; on_stage_now && marker < subject.channels.labelled.size(); ++marker) {
      const Vec3& p = capture.at(index, subject.channels.labelled[marker]);
      if (!is_present(p)) continue;  // occluded: absent from the frame
      LabeledRecon& r = labeled_.emplace_back();
      r.subject_id = subject.info.subject_id;
      r.marker_id = static_cast<uint32_t>(marker);
      r.radius = kMarkerRadiusMm;
      r.position = {p.x(), p.y(), p.z()};
      r.trajectory_id = subject.id_base + static_cast<uint32_t>(subject.channels.labelled[marker]);
    }
    for (size_t k = 0; k < subject.channels.unlabelled.size(); ++k) {
      const Vec3& p = capture.at(index, subject.channels.unlabelled[k]);
      if (!is_present(p)) continue;
      UnlabeledRecon& r = unlabeled_.emplace_back();
      r.radius = kMarkerRadiusMm;
      r.position = {p.x(), p.y(), p.z()};
      r.trajectory_id = subject.id_base + subject.channels.unlabelled_ids[k];
    }
  }
  writer.add(std::span<const LabeledRecon>(labeled_));
  writer.add(std::span<const UnlabeledRecon>(unlabeled_));
}

Timecode CaptureFrameEncoder::timecode_for(uint32_t frame_number, double rate_hz) {
  Timecode tc;
  struct Standard {
    int fps;
    uint32_t id;
  };
  static constexpr Standard kStandards[] = {{24, 3}, {25, 0}, {30, 5}};  // Film, PAL, ATSC
  const long rate = std::lround(rate_hz);
  for (const Standard& s : kStandards) {
    if (rate <= 0 || std::abs(rate_hz - static_cast<double>(rate)) > 1e-9 || rate % s.fps != 0) continue;
    const uint64_t per_frame = static_cast<uint64_t>(rate / s.fps);
    const uint64_t tc_frames = frame_number / per_frame;
    const uint64_t total_seconds = tc_frames / static_cast<uint64_t>(s.fps);
    tc.hours = static_cast<uint8_t>((total_seconds / 3600) % 24);
    tc.minutes = static_cast<uint8_t>((total_seconds / 60) % 60);
    tc.seconds = static_cast<uint8_t>(total_seconds % 60);
    tc.frames = static_cast<uint8_t>(tc_frames % static_cast<uint64_t>(s.fps));
    tc.subframes = static_cast<uint16_t>(frame_number % per_frame);
    tc.subframes_per_frame = static_cast<uint16_t>(per_frame);
    tc.standard = s.id;
    return tc;
  }
  // No standard divides the rate: whole seconds only, standard "none".
  const uint64_t total_seconds = rate_hz > 0.0 ? static_cast<uint64_t>(frame_number / rate_hz) : 0;
  tc.hours = static_cast<uint8_t>((total_seconds / 3600) % 24);
  tc.minutes = static_cast<uint8_t>((total_seconds / 60) % 60);
  tc.seconds = static_cast<uint8_t>(total_seconds % 60);
  return tc;
}

}  // namespace skinstream::vicon
