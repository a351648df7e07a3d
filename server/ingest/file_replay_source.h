#pragma once
// Replays a capture file (C3D/TRC) as a live source: one frame per period / speed, on absolute
// steady-clock deadlines (no drift), frame_number = first_frame + index. The file is one subject
// (named by the caller; by default the file's stem): its labelled channels are the subject's
// labels, its unlabelled ones ("" or "*N") the frame's unlabelled points with the channel as
// their trajectory id. Loops if asked; otherwise ends in the Finished state.

#include <chrono>
#include <string>
#include <vector>

#include "core/capture.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"

namespace skinstream::server {

struct ReplayOptions {
  bool loop = false;
  double speed = 1.0;
  std::string subject_name;  // empty: the file's stem
};

class FileReplaySource : public FrameSource {
 public:
  // Reads the file now; throws FileError when it cannot, or when it has no frames.
  FileReplaySource(asio::io_context& io, const std::string& path, SourceSink& sink, const ReplayOptions& options);
  void start() override;
  void stop() override;

  double rate_hz() const { return capture_.rate_hz; }
  int frame_count() const { return capture_.frame_count; }
  const SourceSubject& subject() const { return frame_.subjects.front(); }

 private:
  void schedule();
  void emit(int index);

  asio::io_context& io_;
  std::string path_;
  Capture capture_;
  SourceSink& sink_;
  ReplayOptions options_;
  std::vector<int> labelled_channels_, unlabelled_channels_;
  SourceFrame frame_;
  asio::steady_timer timer_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::nanoseconds period_{};
  long ticks_ = 0;  // frames played since start (loops included)
  bool running_ = false;
};

}  // namespace skinstream::server
