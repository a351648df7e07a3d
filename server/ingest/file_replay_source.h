#pragma once
// Replays a capture file (C3D/TRC) as a live source: one frame per period / speed, on absolute
// steady-clock deadlines (no drift), channels mapped to the subject's markers exactly as
// fill_capture does (labelled channels the subject does not know become unlabelled points),
// frame_number = first_frame + index. Loops if asked; otherwise ends in the Finished state.

#include <chrono>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/subject_model.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"

namespace skinstream::server {

struct ReplayOptions {
  bool loop = false;
  double speed = 1.0;
};

class FileReplaySource : public FrameSource {
 public:
  // Reads the file now; throws FileError when it cannot, or when no channel names a marker.
  FileReplaySource(asio::io_context& io, const SubjectModel& model, const std::string& path, FrameSink& sink,
                   const ReplayOptions& options);
  void start() override;
  void stop() override;

  double rate_hz() const { return capture_.rate_hz; }
  int frame_count() const { return capture_.frame_count; }

 private:
  void schedule();
  void emit(int index);

  asio::io_context& io_;
  std::string path_;
  Capture capture_;
  FrameSink& sink_;
  ReplayOptions options_;
  std::vector<int> channel_of_;     // per subject marker
  std::vector<int> free_channels_;  // channels that are not a subject marker
  std::vector<std::string> unknown_labels_;
  MarkerFrame frame_;
  asio::steady_timer timer_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::nanoseconds period_{};
  long ticks_ = 0;  // frames played since start (loops included)
  bool running_ = false;
};

}  // namespace skinstream::server
