#pragma once
// A subject changed while the daemon serves it, without a restart and without its subscribers
// reconnecting (docs/control-api.md): a live calibration (N seconds of the subject's range of
// motion recorded from the stream, built into a subject file by `skinstream build-subject` in a
// separate process at a low priority, with the real-actor checks), or another subject file.
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
  // What the daemon does for a change on its io thread.
  class Host {
   public:
    virtual ~Host() = default;
    // Runs `job` on the io thread, between two frames, and waits for it; false when the daemon
    // stops first (the job then never runs).
    virtual bool run_on_io_thread(const std::function<void()>& job) = 0;
    // The io thread: `subject`'s router target is its new model's (SubjectStream::target()).
    virtual void retarget(SubjectStream& subject) = 0;
    // Any thread: the source's rate (0: not known yet).
    virtual double source_rate_hz() const = 0;
    // This object's thread (slow): a new subject's stream, as the daemon would make it at
    // start-up, not started. Throws FileError or ConfigError with the reason.
    virtual std::unique_ptr<SubjectStream> make_subject(const std::string& name, const std::string& file) = 0;
    // The io thread: `subject` routed, listed and started.
    virtual void insert_subject(std::unique_ptr<SubjectStream> subject) = 0;
    // The io thread: subject `name` no longer routed nor listed; its subscribers told and closed.
    // 409 when it cannot go (the last subject).
    virtual ControlAnswer remove_subject(const std::string& name, const std::string& who) = 0;
  };

  // `subjects` (those served at start) outlive this object, as do those added later until they
  // are removed; `recorder` may be null (no record_dir).
  SubjectChanges(SubjectChangesOptions options, const std::vector<SubjectStream*>& subjects, Host& host,
                 TakeRecorder* recorder);
  ~SubjectChanges();  // kills a build under way, then joins the thread
  SubjectChanges(const SubjectChanges&) = delete;
  SubjectChanges& operator=(const SubjectChanges&) = delete;

  // The io thread (control API). 202 with the change's state, or why it cannot start.
  ControlAnswer calibrate(const std::string& name, const nlohmann::json& request, const std::string& who);
  ControlAnswer load_file(const std::string& name, const nlohmann::json& request, const std::string& who);
  ControlAnswer add(const nlohmann::json& request, const std::string& who);  // {"name", "file"}
  ControlAnswer remove(const std::string& name, const std::string& who);     // 200 once removed
  ControlAnswer state(const std::string& name) const;
  ControlAnswer list() const;

  // The io thread, for every frame routed to `subject` (cheap when no calibration records).
  void on_routed(const SubjectStream& subject, const MarkerFrame& frame) {
    if (capturing_count_ > 0) capture_frame(subject, frame);
  }
  // The io thread: /health's "change" of subject `name`: the last change asked for (null when none).
  nlohmann::json health(const std::string& name) const;

 private:
  // One subject as changes see it: served (stream) or being added (null until inserted).
  struct Entry {
    std::string name;
    SubjectStream* stream = nullptr;
    std::unique_ptr<CalibrationCapture> capture;  // io thread: while a calibration records
    std::string capture_mesh;
    nlohmann::json change;                                 // under mutex_: the last change (null when none)
    std::chrono::steady_clock::time_point change_started;  // under mutex_: when it was asked for
  };
  std::shared_ptr<Entry> find(const std::string& name) const;
  // 409 when a change of `entry` is under way; else a new change in state `state`.
  ControlAnswer begin(Entry& entry, const std::string& kind, const std::string& state, const std::string& who,
                      nlohmann::json details);
  void capture_frame(const SubjectStream& subject, const MarkerFrame& frame);
  void post(std::function<void()> job);
  void run();
  // On this object's thread.
  void build_and_swap(const std::shared_ptr<Entry>& entry, Capture capture, std::string mesh);
  void swap_in(const std::shared_ptr<Entry>& entry, const std::string& file);
  void add_subject(const std::shared_ptr<Entry>& entry, const std::string& file);
  void update(Entry& entry, const std::function<void(nlohmann::json&)>& edit);
  void fail(Entry& entry, const std::string& reason);

  SubjectChangesOptions options_;
  Host& host_;
  TakeRecorder* recorder_;

  std::vector<std::shared_ptr<Entry>> entries_;  // the io thread's; the jobs hold theirs
  int capturing_count_ = 0;                      // io thread

  mutable std::mutex mutex_;  // every entry's change, and the jobs
  std::deque<std::function<void()>> jobs_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::atomic<bool> cancel_{false};
  std::thread thread_;  // last: started once the rest is made
};

}  // namespace skinstream::server
