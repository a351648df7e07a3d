#include "protocol/vicon_capture_encoder.h"

#include <charconv>
#include <cmath>

namespace skinstream::vicon {
namespace {

constexpr double kMarkerRadiusMm = 7.0;  // a 14 mm marker; the SDK does not use it for positions

// "*12" -> 12; "" (or anything unparsable) -> the channel index.
uint32_t unlabelled_id(const std::string& label, int channel) {
  uint32_t id = 0;
  if (label.size() > 1 && label[0] == '*') {
    const auto [end, ec] = std::from_chars(label.data() + 1, label.data() + label.size(), id);
    if (ec == std::errc() && end == label.data() + label.size()) return id;
  }
  return static_cast<uint32_t>(channel);
}

}  // namespace

CaptureFrameEncoder::CaptureFrameEncoder(const Capture& capture, std::string subject_name, double rate_hz)
    : capture_(capture), rate_hz_(rate_hz > 0.0 ? rate_hz : capture.rate_hz) {
  stream_info_.frame_period_ticks = frame_period_ticks(rate_hz_);
  subject_info_.subject_id = kSubjectId;
  subject_info_.name = std::move(subject_name);
  for (int channel = 0; channel < capture.point_count(); ++channel) {
    if (capture.is_labelled(channel)) {
      subject_info_.markers.push_back({static_cast<uint32_t>(labelled_channels_.size()), capture.labels[channel]});
      labelled_channels_.push_back(channel);
    } else {
      unlabelled_channels_.push_back(channel);
      unlabelled_ids_.push_back(unlabelled_id(capture.labels[channel], channel));
    }
  }
  labeled_.reserve(labelled_channels_.size());
  unlabeled_.reserve(unlabelled_channels_.size());
}

ObjectEnums CaptureFrameEncoder::offered_types() {
  return {{object_type::StreamInfo, object_type::SubjectInfo, object_type::FrameInfo, object_type::LabeledRecons,
           object_type::UnlabeledRecons, object_type::Timecode, object_type::Ping, object_type::Contents}};
}

void CaptureFrameEncoder::encode_frame(int index, uint32_t frame_number, bool include_static, PacketWriter& writer) {
  writer.begin();
  if (include_static) {
    writer.add(stream_info_);
    writer.add(subject_info_);
  }
  writer.add(FrameInfo{frame_number - 1});  // the SDK reports FrameInfo + 1
  writer.add(timecode_for(frame_number, rate_hz_));
  labeled_.clear();
  for (size_t marker = 0; marker < labelled_channels_.size(); ++marker) {
    const Vec3& p = capture_.at(index, labelled_channels_[marker]);
    if (!is_present(p)) continue;  // occluded: absent from the frame
    LabeledRecon& r = labeled_.emplace_back();
    r.subject_id = kSubjectId;
    r.marker_id = static_cast<uint32_t>(marker);
    r.radius = kMarkerRadiusMm;
    r.position = {p.x(), p.y(), p.z()};
    r.trajectory_id = static_cast<uint32_t>(labelled_channels_[marker]);
  }
  writer.add(std::span<const LabeledRecon>(labeled_));
  unlabeled_.clear();
  for (size_t k = 0; k < unlabelled_channels_.size(); ++k) {
    const Vec3& p = capture_.at(index, unlabelled_channels_[k]);
    if (!is_present(p)) continue;
    UnlabeledRecon& r = unlabeled_.emplace_back();
    r.radius = kMarkerRadiusMm;
    r.position = {p.x(), p.y(), p.z()};
    r.trajectory_id = unlabelled_ids_[k];
  }
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
