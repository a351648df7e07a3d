#pragma once
// Takes recorded by the daemon: for every subject, what it received (labelled markers,
// unlabelled points, missing samples; the source's frame numbers, times and timecode) and what
// it published (the filled markers and how each sample was obtained), a take a folder:
//
//   RECORD_DIR/TAKE/take.json          what the take is (subjects, subject files' SHA-256,
//                                       config, who started it, counts, state)
//   RECORD_DIR/TAKE/SUBJECT.raw.c3d     received markers, then "*1".."*N" unlabelled slots
//   RECORD_DIR/TAKE/SUBJECT.raw.tsv     per frame: source frame, times, timecode, counts
//   RECORD_DIR/TAKE/SUBJECT.filled.c3d  published markers
//   RECORD_DIR/TAKE/SUBJECT.filled.tsv  per frame: source frame, times, each sample's status
//
// The stream's threads only copy frames into each subject's TakeTap; this recorder's own
// thread (at a low priority) writes them, and twice a second syncs every file and then the
// counts that make it readable, so a take survives kill -9 up to its last half second (the C3D
// files are valid at every moment: protocol/files/c3d_take_writer.h). A disk that refuses
// stops the take, says why in /health and the log, and the stream goes on. At start the
// recorder closes takes an earlier daemon left open (recover_interrupted()).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/record/take_tap.h"

namespace skinstream::server {

struct TakeRecorderOptions {
  std::filesystem::path dir;   // where takes go (created when missing)
  int unlabelled_slots = 256;  // unlabelled channels of a received take (server/record/unlabelled_slots.h)
  std::chrono::milliseconds commit_interval{500};  // a crash loses at most about this much
  size_t ring_frames = 480;        // frames a subject's rings hold for the writer (4 s at 120 Hz)
  double default_rate_hz = 120.0;  // the C3D rate when the source has not said yet
  nlohmann::json config;           // the daemon's configuration, kept in each take's take.json
};

// What a control call gets back: an HTTP status and a JSON body.
struct TakeAnswer {
  int status = 200;
  nlohmann::json body;
};

class TakeRecorder {
 public:
  explicit TakeRecorder(TakeRecorderOptions options);
  ~TakeRecorder();  // stops a take in progress (closing its files) and the thread
  TakeRecorder(const TakeRecorder&) = delete;
  TakeRecorder& operator=(const TakeRecorder&) = delete;

  // Before start_thread(), for every subject served: its tap, valid as long as the recorder.
  TakeTap& add_subject(const std::string& name, const std::string& subject_file,
                       std::vector<std::string> marker_names);
  // Before start_thread(): closes the takes an earlier daemon left recording (killed, or its
  // disk full) and says what each held, a line each (also kept for /health).
  std::vector<std::string> recover_interrupted();
  void start_thread();

  // Any thread: the subject file of subject `name` from the next take on (a swap); a take in
  // progress keeps the one it began with. The markers stay those add_subject() was given.
  void set_subject_file(const std::string& name, const std::string& subject_file);
  // The marker names subject `name` is recorded with (empty when it is not recorded).
  std::vector<std::string> recorded_marker_names(const std::string& name) const;

  // Any thread, quick (creates the take's folder; the files are made on the recorder's thread).
  // `name` empty: named by the UTC time. 201, or 409 when a take is recording or the name is
  // taken, 400 for a bad name, 500 when the folder cannot be made.
  TakeAnswer start(const std::string& name, const std::string& who);
  // Any thread, quick: 200 (the files are closed on the recorder's thread), 409 when none records.
  TakeAnswer stop(const std::string& who);
  // The takes in the folder, newest first (at most 100), each as its take.json says.
  nlohmann::json list() const;
  nlohmann::json health() const;  // /health's "recording"

  // Checks a take name: letters, digits, '-', '_', '.', at most 64, not starting with '.'.
  static bool valid_take_name(const std::string& name);

 private:
  struct SubjectEntry {
    std::unique_ptr<TakeTap> tap;
    std::string subject_file;  // under mutex_ once the thread runs
    std::string file_stem;     // the subject's name made safe for a file name, unique in the take
  };
  struct ActiveTake;
  enum class State { Idle, Recording, Stopping, Failed };

  void run();
  void begin_take(ActiveTake& take);
  void drain(ActiveTake& take);
  void commit(ActiveTake& take);
  void finish_take(ActiveTake& take, const std::string& state);
  void fail_take(ActiveTake& take, const std::string& reason);
  void write_sidecar(const ActiveTake& take, const std::string& state) const;
  void publish_progress(const ActiveTake& take);

  TakeRecorderOptions options_;
  std::vector<SubjectEntry> subjects_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_thread_ = false;
  State state_ = State::Idle;
  std::unique_ptr<ActiveTake> pending_start_;  // handed to the thread
  bool pending_stop_ = false;
  uint64_t next_take_id_ = 0;
  // What /health says (under mutex_, refreshed by the thread every commit).
  std::string take_name_, take_who_, last_error_;
  std::chrono::system_clock::time_point take_started_{};
  nlohmann::json progress_ = nlohmann::json::object();
  std::vector<std::string> recovered_;
  uint64_t takes_closed_ = 0, takes_failed_ = 0;

  std::thread thread_;
};

}  // namespace skinstream::server
