#pragma once
// A subject changed while the daemon serves it, without a restart and without its subscribers
// reconnecting (docs/control-api.md): a live calibration (N seconds of the subject's range of
// motion recorded from the stream, built into a subject file by `skinstream build-subject` in a
// separate process at the lowest priority, with the real-actor checks), or another subject file.
// Either way the new subject file is read and checked as at start-up and swapped in between two
// frames (SubjectStream's three steps); when anything fails, the served subject stays and the
// reason is kept for /health and GET /subjects/NAME.
//
// The io thread only starts a change and copies the calibration's frames (CalibrationCapture);
// the rest runs on this object's own thread, one change at a time.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/control/control_actions.h"
#include "server/ingest/marker_frame.h"
#include "server/subjects/calibration_capture.h"

namespace skinstream::server {

class SubjectStream;
class TakeRecorder;

struct SubjectChangesOptions {
  std::filesystem::path dir;       // the calibrations' takes, reports and subject files
  std::string builder;             // the skinstream program (default_subject_builder())
  std::string mesh;                // a calibration's body mesh when the request names none
  double default_rate_hz = 120.0;  // the calibration's frames per second when the source has not said
  int max_seconds = 120;           // the longest range of motion asked for
  std::chrono::seconds build_timeout{600};
};

class SubjectChanges {
 public:
  // What the daemon does for a swap on its io thread.
  class Host {
   public:
    virtual ~Host() = default;
    // Runs `job` on the io thread, between two frames, and waits for it; false when the daemon
    // stops first (the job then never runs).
    virtual bool run_on_io_thread(const std::function<void()>& job) = 0;
    // The io thread: subject `index`'s router target is its new model's (SubjectStream::target()).
    virtual void retarget(int index) = 0;
    // Any thread: the source's rate (0: not known yet).
    virtual double source_rate_hz() const = 0;
  };

  // `subjects` outlive this object; `recorder` may be null (no record_dir).
  SubjectChanges(SubjectChangesOptions options, std::vector<SubjectStream*> subjects, Host& host,
                 TakeRecorder* recorder);
  ~SubjectChanges();  // kills a build under way, then joins the thread
  SubjectChanges(const SubjectChanges&) = delete;
  SubjectChanges& operator=(const SubjectChanges&) = delete;

  // The io thread (control API). 202 with the change's state, or why it cannot start.
  ControlAnswer calibrate(const std::string& name, const nlohmann::json& request, const std::string& who);
  ControlAnswer load_file(const std::string& name, const nlohmann::json& request, const std::string& who);
  ControlAnswer state(const std::string& name) const;
  ControlAnswer list() const;

  // The io thread, for every frame routed to subject `index` (cheap when no calibration records).
  void on_routed(int index, const MarkerFrame& frame) {
    if (capturing_count_ > 0) capture_frame(index, frame);
  }
  // /health's "change" of subject `index`: the last change asked for (null when none).
  nlohmann::json health(int index) const;

 private:
  int index_of(const std::string& name) const;
  // 409 when a change of `index` is under way; else a new change in state `state`.
  ControlAnswer begin(int index, const std::string& kind, const std::string& state, const std::string& who,
                      nlohmann::json details);
  void capture_frame(int index, const MarkerFrame& frame);
  void post(std::function<void()> job);
  void run();
  // On this object's thread.
  void build_and_swap(int index, Capture capture, std::string mesh);
  void swap_in(int index, const std::string& file);
  void update(int index, const std::function<void(nlohmann::json&)>& edit);
  void fail(int index, const std::string& reason);

  SubjectChangesOptions options_;
  std::vector<SubjectStream*> subjects_;
  Host& host_;
  TakeRecorder* recorder_;

  // The io thread only: each subject's calibration recording, while it records.
  std::vector<std::unique_ptr<CalibrationCapture>> captures_;
  std::vector<std::string> capture_meshes_;
  int capturing_count_ = 0;

  mutable std::mutex mutex_;
  std::vector<nlohmann::json> changes_;  // per subject: its last change (null when none)
  std::deque<std::function<void()>> jobs_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::atomic<bool> cancel_{false};
  std::thread thread_;  // last: started once the rest is made
};

}  // namespace skinstream::server
