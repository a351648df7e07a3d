#include "server/ingest/file_replay_source.h"

#include "core/capture_filler.h"
#include "protocol/capture_file.h"
#include "protocol/file_error.h"

namespace skinstream::server {

FileReplaySource::FileReplaySource(asio::io_context& io, const SubjectModel& model, const std::string& path,
                                   FrameSink& sink, const ReplayOptions& options)
    : io_(io), path_(path), capture_(read_capture(path)), sink_(sink), options_(options), frame_(model.marker_count()),
      timer_(io) {
  CaptureFillReport report;
  channel_of_ = map_channels_to_markers(model, capture_, &report);
  if (capture_.frame_count == 0) throw FileError(path, "the capture has no frames");
  if (channel_of_ == std::vector<int>(model.marker_count(), -1))
    throw FileError(path, "none of the subject's " + std::to_string(model.marker_count()) +
                              " marker labels is in this capture (wrong subject file?)");
  std::vector<char> is_marker_channel(capture_.point_count(), 0);
  for (int c : channel_of_)
    if (c >= 0) is_marker_channel[c] = 1;
  for (int c = 0; c < capture_.point_count(); ++c)
    if (!is_marker_channel[c]) free_channels_.push_back(c);
  unknown_labels_ = report.unknown_labels;
  const double rate = capture_.rate_hz > 0 ? capture_.rate_hz : 120.0;
  period_ = std::chrono::nanoseconds(static_cast<long long>(1e9 / (rate * options_.speed)));
}

void FileReplaySource::start() {
  running_ = true;
  for (const std::string& name : unknown_labels_) sink_.on_unknown_label(name);
  sink_.on_source_state(SourceState::Streaming, "replay " + path_);
  start_ = std::chrono::steady_clock::now();
  ticks_ = 0;
  schedule();
}

void FileReplaySource::stop() {
  running_ = false;
  timer_.cancel();
}

void FileReplaySource::schedule() {
  timer_.expires_at(start_ + period_ * ticks_);
  timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || !running_) return;
    const int index = static_cast<int>(ticks_ % capture_.frame_count);
    if (index == 0 && ticks_ > 0) {
      if (!options_.loop) {
        running_ = false;
        sink_.on_source_state(SourceState::Finished, "replay " + path_ + " ended after " +
                                                         std::to_string(capture_.frame_count) + " frames");
        return;
      }
      // A new take as far as the filler is concerned.
      sink_.on_source_state(SourceState::Streaming, "replay " + path_ + " looped");
    }
    emit(index);
    ++ticks_;
    schedule();
  });
}

void FileReplaySource::emit(int index) {
  frame_.clear();
  frame_.frame_number = static_cast<uint32_t>(capture_.first_frame + index);
  const double rate = capture_.rate_hz > 0 ? capture_.rate_hz : 120.0;
  frame_.source_time_ns = static_cast<int64_t>(1e9 * index / rate);
  frame_.source_rate_hz = capture_.rate_hz;
  frame_.receive_time_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  for (size_t m = 0; m < channel_of_.size(); ++m)
    frame_.labelled[m] = channel_of_[m] >= 0 ? capture_.at(index, channel_of_[m]) : missing_point();
  for (int c : free_channels_) {
    if (!capture_.present(index, c)) continue;
    if (frame_.unlabelled_count == MarkerFrame::kMaxUnlabelled) {
      ++frame_.rejected_points;
      continue;
    }
    frame_.unlabelled[frame_.unlabelled_count] = capture_.at(index, c);
    frame_.unlabelled_ids[frame_.unlabelled_count] = c;  // a channel is one trajectory fragment
    ++frame_.unlabelled_count;
  }
  sink_.on_frame(frame_);
}

}  // namespace skinstream::server
