#include "server/ingest/file_replay_source.h"

#include <filesystem>

#include "protocol/files/capture_file.h"
#include "protocol/files/file_error.h"

namespace skinstream::server {

FileReplaySource::FileReplaySource(asio::io_context& io, const std::string& path, SourceSink& sink,
                                   const ReplayOptions& options)
    : io_(io), path_(path), capture_(read_capture(path)), sink_(sink), options_(options), timer_(io) {
  if (capture_.frame_count == 0) throw FileError(path, "the capture has no frames");
  labelled_channels_ = capture_.labelled_points();
  unlabelled_channels_ = capture_.unlabelled_points();
  SourceSubject& subject = frame_.subjects.emplace_back();
  subject.name = options.subject_name.empty() ? std::filesystem::path(path).stem().string() : options.subject_name;
  for (int c : labelled_channels_) subject.labels.push_back(capture_.labels[c]);
  frame_.labelled.assign(1, std::vector<Vec3>(labelled_channels_.size(), missing_point()));
  frame_.unlabelled.reserve(unlabelled_channels_.size());
  frame_.unlabelled_ids.reserve(unlabelled_channels_.size());
  frame_.structure_version = 1;
  frame_.rate_hz = capture_.rate_hz;
  const double rate = capture_.rate_hz > 0 ? capture_.rate_hz : 120.0;
  period_ = std::chrono::nanoseconds(static_cast<long long>(1e9 / (rate * options_.speed)));
}

void FileReplaySource::start() {
  running_ = true;
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
  frame_.frame_number = static_cast<uint32_t>(capture_.first_frame + index);
  const double rate = capture_.rate_hz > 0 ? capture_.rate_hz : 120.0;
  frame_.source_time_ns = static_cast<int64_t>(1e9 * index / rate);
  frame_.receive_time_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::vector<Vec3>& labelled = frame_.labelled.front();
  for (size_t l = 0; l < labelled_channels_.size(); ++l) labelled[l] = capture_.at(index, labelled_channels_[l]);
  frame_.unlabelled.clear();
  frame_.unlabelled_ids.clear();
  for (int c : unlabelled_channels_) {
    if (!capture_.present(index, c)) continue;
    frame_.unlabelled.push_back(capture_.at(index, c));
    frame_.unlabelled_ids.push_back(c);  // a channel is one trajectory fragment
  }
  sink_.on_frame(frame_);
}

}  // namespace skinstream::server
