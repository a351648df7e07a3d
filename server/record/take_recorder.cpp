#include "server/record/take_recorder.h"

#include <openssl/evp.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <fstream>
#include <iterator>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include "core/marker_status.h"
#include "protocol/files/c3d_take_writer.h"
#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"
#include "server/file_naming.h"
#include "server/record/frame_table.h"
#include "server/record/unlabelled_slots.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

constexpr size_t kMaxTakeName = 64;
constexpr size_t kMaxListedTakes = 100;
constexpr std::chrono::milliseconds kDrainInterval{50};
// The writer is a background job: it yields the CPU to the stream's threads.
constexpr int kRecorderNice = 10;

std::string sha256_of_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  EVP_DigestInit_ex(context, EVP_sha256(), nullptr);
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    EVP_DigestUpdate(context, buffer.data(), static_cast<size_t>(in.gcount()));
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  EVP_MD_CTX_free(context);
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) fmt::format_to(std::back_inserter(hex), "{:02x}", digest[i]);
  return hex;
}

char status_letter(uint8_t status) {
  switch (static_cast<MarkerStatus>(status)) {
    case MarkerStatus::Measured:
      return 'M';
    case MarkerStatus::Relabelled:
      return 'R';
    case MarkerStatus::FilledPca:
      return 'P';
    case MarkerStatus::FilledRigid:
      return 'G';
    case MarkerStatus::Held:
      return 'H';
  }
  return '?';
}

void append_timecode(std::string& line, const SourceTimecode& tc) {
  if (!tc.valid) {
    line += '-';
    return;
  }
  fmt::format_to(std::back_inserter(line), "{:02}:{:02}:{:02}{}{:02}", tc.hours, tc.minutes, tc.seconds,
                 tc.drop_frame ? ';' : ':', tc.frames);
  if (tc.subframes_per_frame > 0)
    fmt::format_to(std::back_inserter(line), ".{}/{}", tc.subframe, tc.subframes_per_frame);
}

const char* const kRawTableHeader =
    "frame\tsource_frame\tsource_time_ns\treceive_time_ns\ttimecode\tunlabelled\tunlabelled_kept\tunknown_"
    "labels";
const char* const kFilledTableHeader = "frame\tsource_frame\tsource_time_ns\treceive_time_ns\tstatus";

// take.json written whole beside, then renamed over: a reader sees the old or the new (not synced:
// a kill leaves it whole; after a power loss the C3D files and tables are what was synced).
void write_json_atomically(const std::filesystem::path& path, const nlohmann::json& json) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << json.dump(2) << '\n';
    out.flush();
    if (!out) throw FileError(temporary.string(), "cannot write");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw FileError(path.string(), "cannot replace: " + ec.message());
}

std::optional<nlohmann::json> read_sidecar(const std::filesystem::path& path, std::string* error = nullptr) {
  try {
    return nlohmann::json::parse(read_whole_file(path.string(), {1 << 22, "take.json"}));
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return std::nullopt;
  }
}

}  // namespace

struct TakeRecorder::ActiveTake {
  struct Files {
    SubjectEntry* subject = nullptr;
    double rate_hz = 0.0;
    std::string subject_file, subject_sha256;  // as the take began
    std::unique_ptr<C3dTakeWriter> raw_c3d, filled_c3d;
    std::unique_ptr<FrameTable> raw_table, filled_table;
    std::unique_ptr<UnlabelledSlots> unlabelled;
    std::vector<Vec3> raw_points;  // a received frame with its unlabelled points in their channels
    std::vector<int> slot_of_point;
    uint64_t raw_frames = 0, filled_frames = 0;
    uint64_t raw_dropped_before = 0, filled_dropped_before = 0;  // the tap's counts when the take began
  };
  uint64_t id = 0;
  std::string name, who;
  std::filesystem::path folder;
  std::chrono::system_clock::time_point started;
  std::chrono::steady_clock::time_point last_commit;
  std::vector<Files> files;
};

TakeRecorder::TakeRecorder(TakeRecorderOptions options) : options_(std::move(options)) {
  // A folder that cannot be made is reported (/health, the log, each start's answer), not fatal:
  // the stream matters more on a stage than the recording.
  std::error_code ec;
  std::filesystem::create_directories(options_.dir, ec);
  if (ec || !std::filesystem::is_directory(options_.dir, ec)) {
    state_ = State::Failed;
    last_error_ =
        "cannot make the takes folder " + options_.dir.string() + ": " + (ec ? ec.message() : "not a folder");
    spdlog::error("recording: {} (the stream goes on without it)", last_error_);
  }
}

TakeRecorder::~TakeRecorder() {
  {
    std::lock_guard lock(mutex_);
    stopping_thread_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool TakeRecorder::valid_take_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxTakeName || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
  });
}

TakeTap& TakeRecorder::add_subject(const std::string& name, const std::string& subject_file,
                                   std::vector<std::string> marker_names) {
  std::string stem = file_stem_of(name);
  for (int n = 2; std::any_of(subjects_.begin(), subjects_.end(),
                              [&](const SubjectEntry& s) { return s.file_stem == stem; });
       ++n)
    stem = file_stem_of(name) + "-" + std::to_string(n);
  SubjectEntry entry;
  entry.tap = std::make_unique<TakeTap>(name, std::move(marker_names), options_.unlabelled_slots,
                                        options_.ring_frames);
  entry.subject_file = subject_file;
  entry.file_stem = stem;
  subjects_.push_back(std::move(entry));
  return *subjects_.back().tap;
}

void TakeRecorder::set_subject_file(const std::string& name, const std::string& subject_file) {
  std::lock_guard lock(mutex_);
  for (SubjectEntry& subject : subjects_)
    if (subject.tap->subject() == name) subject.subject_file = subject_file;
}

std::vector<std::string> TakeRecorder::recorded_marker_names(const std::string& name) const {
  for (const SubjectEntry& subject : subjects_)
    if (subject.tap->subject() == name) return subject.tap->marker_names();
  return {};
}

void TakeRecorder::start_thread() {
  thread_ = std::thread([this] { run(); });
}

TakeAnswer TakeRecorder::start(const std::string& requested, const std::string& who) {
  const auto now = std::chrono::system_clock::now();
  const std::string name = requested.empty() ? utc_text(now, "take-%Y%m%d-%H%M%S") : requested;
  if (!valid_take_name(name))
    return {400, {{"error", "a take name is 1-64 letters, digits, '-', '_' or '.', not starting with '.'"}}};
  std::lock_guard lock(mutex_);
  if (state_ == State::Recording || state_ == State::Stopping)
    return {409,
            {{"error", "take " + take_name_ + " is " +
                           (state_ == State::Recording ? "recording" : "closing") + ": stop it first"}}};
  const std::filesystem::path folder = options_.dir / name;
  std::error_code ec;
  if (std::filesystem::exists(folder, ec)) return {409, {{"error", "a take named " + name + " exists"}}};
  if (!std::filesystem::create_directory(folder, ec) || ec)
    return {500, {{"error", "cannot make " + folder.string() + ": " + (ec ? ec.message() : "it exists")}}};

  auto take = std::make_unique<ActiveTake>();
  take->id = ++next_take_id_;
  take->name = name;
  take->who = who;
  take->folder = folder;
  take->started = now;
  pending_start_ = std::move(take);
  state_ = State::Recording;
  take_name_ = name;
  take_who_ = who;
  take_started_ = now;
  last_error_.clear();
  progress_ = nlohmann::json::object();
  // From this frame on, the streams copy their frames for the take; its files are being made.
  for (SubjectEntry& subject : subjects_) subject.tap->set_take(next_take_id_);
  wake_.notify_all();
  spdlog::info("take {} started by {}: recording {} subject(s) into {}", name, who, subjects_.size(),
               folder.string());
  return {201, {{"take", name}, {"state", "recording"}, {"folder", folder.string()}}};
}

TakeAnswer TakeRecorder::stop(const std::string& who) {
  std::lock_guard lock(mutex_);
  if (state_ != State::Recording) return {409, {{"error", "no take is recording"}}};
  for (SubjectEntry& subject : subjects_) subject.tap->set_take(0);
  pending_stop_ = true;
  state_ = State::Stopping;
  wake_.notify_all();
  spdlog::info("take {} stopped by {}", take_name_, who);
  return {200, {{"take", take_name_}, {"state", "closing"}}};
}

void TakeRecorder::run() {
  name_this_thread("recorder");
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kRecorderNice);
  std::unique_ptr<ActiveTake> take;
  for (;;) {
    std::unique_ptr<ActiveTake> starting;
    bool stop_asked = false, exiting = false;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, kDrainInterval,
                     [&] { return stopping_thread_ || pending_start_ || pending_stop_; });
      starting = std::move(pending_start_);
      stop_asked = pending_stop_;
      pending_stop_ = false;
      exiting = stopping_thread_;
    }
    try {
      if (starting) {
        take = std::move(starting);
        begin_take(*take);
      }
      if (take) {
        drain(*take);
        if (stop_asked || exiting) {
          finish_take(*take, "closed");
          take.reset();
        } else if (std::chrono::steady_clock::now() - take->last_commit >= options_.commit_interval) {
          commit(*take);
        }
      } else {
        for (SubjectEntry& subject : subjects_) {  // frames of a take that failed or was stopped
          while (subject.tap->received().front()) subject.tap->received().pop();
          while (subject.tap->published().front()) subject.tap->published().pop();
        }
      }
    } catch (const std::exception& e) {
      if (take) fail_take(*take, e.what());
      take.reset();
    }
    if (exiting) break;
  }
}

void TakeRecorder::begin_take(ActiveTake& take) {
  for (SubjectEntry& subject : subjects_) {
    ActiveTake::Files files;
    files.subject = &subject;
    const double rate = subject.tap->source_rate_hz();
    files.rate_hz = rate > 0 ? rate : options_.default_rate_hz;
    {
      std::lock_guard lock(mutex_);
      files.subject_file = subject.subject_file;
    }
    files.subject_sha256 = sha256_of_file(files.subject_file);
    files.raw_dropped_before = subject.tap->received_dropped();
    files.unlabelled = std::make_unique<UnlabelledSlots>(subject.tap->unlabelled_slots());
    files.raw_points.resize(subject.tap->marker_names().size() +
                            static_cast<size_t>(subject.tap->unlabelled_slots()));
    files.slot_of_point.resize(static_cast<size_t>(subject.tap->unlabelled_slots()));
    files.filled_dropped_before = subject.tap->published_dropped();
    take.files.push_back(std::move(files));
  }
  // The sidecar first: whatever happens next, a restart finds the take and what it was to hold.
  write_sidecar(take, "recording");
  for (ActiveTake::Files& files : take.files) {
    const TakeTap& tap = *files.subject->tap;
    const std::string base = (take.folder / files.subject->file_stem).string();
    files.raw_c3d = std::make_unique<C3dTakeWriter>(base + ".raw.c3d", tap.received_labels(), files.rate_hz);
    files.raw_table = std::make_unique<FrameTable>(base + ".raw.tsv", kRawTableHeader);
    files.filled_c3d =
        std::make_unique<C3dTakeWriter>(base + ".filled.c3d", tap.marker_names(), files.rate_hz);
    files.filled_table = std::make_unique<FrameTable>(base + ".filled.tsv", kFilledTableHeader);
  }
  take.last_commit = std::chrono::steady_clock::now();
}

void TakeRecorder::drain(ActiveTake& take) {
  for (ActiveTake::Files& files : take.files) {
    RecordedFrameRing& received = files.subject->tap->received();
    while (const RecordedFrame* frame = received.front()) {
      if (frame->take == take.id) {
        const size_t markers = files.subject->tap->marker_names().size();
        const auto copied = static_cast<size_t>(frame->unlabelled_copied);
        const int kept = files.unlabelled->assign(std::span<const int>(frame->unlabelled_ids).first(copied),
                                                  std::span<int>(files.slot_of_point).first(copied));
        std::copy_n(frame->points.begin(), markers, files.raw_points.begin());
        std::fill(files.raw_points.begin() + static_cast<long>(markers), files.raw_points.end(),
                  missing_point());
        for (size_t j = 0; j < copied; ++j)
          if (files.slot_of_point[j] >= 0)
            files.raw_points[markers + static_cast<size_t>(files.slot_of_point[j])] =
                frame->points[markers + j];
        files.raw_c3d->append(files.raw_points);
        std::string& line = files.raw_table->line();
        fmt::format_to(std::back_inserter(line), "{}\t{}\t{}\t{}\t", ++files.raw_frames, frame->frame_number,
                       frame->source_time_ns, frame->receive_time_ns);
        append_timecode(line, frame->timecode);
        fmt::format_to(std::back_inserter(line), "\t{}\t{}\t{}\n", frame->unlabelled, kept,
                       frame->unknown_labels);
      }
      received.pop();
    }
    RecordedFrameRing& published = files.subject->tap->published();
    while (const RecordedFrame* frame = published.front()) {
      if (frame->take == take.id) {
        files.filled_c3d->append(frame->points);
        std::string& line = files.filled_table->line();
        fmt::format_to(std::back_inserter(line), "{}\t{}\t{}\t{}\t", ++files.filled_frames,
                       frame->frame_number, frame->source_time_ns, frame->receive_time_ns);
        for (uint8_t status : frame->status) line += status_letter(status);
        line += '\n';
      }
      published.pop();
    }
  }
}

void TakeRecorder::commit(ActiveTake& take) {
  // The tables first: a table never says less than its C3D file after a crash.
  for (ActiveTake::Files& files : take.files) {
    files.raw_table->commit();
    files.filled_table->commit();
    files.raw_c3d->commit();
    files.filled_c3d->commit();
  }
  take.last_commit = std::chrono::steady_clock::now();
  publish_progress(take);
}

void TakeRecorder::finish_take(ActiveTake& take, const std::string& state) {
  for (ActiveTake::Files& files : take.files) {
    files.raw_table->close();
    files.filled_table->close();
    files.raw_c3d->close();
    files.filled_c3d->close();
  }
  write_sidecar(take, state);
  publish_progress(take);
  std::string summary;
  for (const ActiveTake::Files& files : take.files)
    summary += fmt::format("; {}: {} received, {} published ({:.1f} s)", files.subject->tap->subject(),
                           files.raw_frames, files.filled_frames,
                           static_cast<double>(files.raw_frames) / files.rate_hz);
  spdlog::info("take {} closed{}", take.name, summary);
  std::lock_guard lock(mutex_);
  state_ = State::Idle;
  ++takes_closed_;
}

void TakeRecorder::fail_take(ActiveTake& take, const std::string& reason) {
  for (SubjectEntry& subject : subjects_) subject.tap->set_take(0);
  {
    std::lock_guard lock(mutex_);
    last_error_ = reason;
  }
  spdlog::error("take {} stopped: {} (its files read up to the last second written; the stream goes on)",
                take.name, reason);
  try {
    write_sidecar(take, "failed");
  } catch (const std::exception&) {
    // The disk that refused the frames may refuse this too: a restart closes the take.
  }
  publish_progress(take);
  take.files.clear();  // closes the files without another write
  std::lock_guard lock(mutex_);
  state_ = State::Failed;
  ++takes_failed_;
}

void TakeRecorder::publish_progress(const ActiveTake& take) {
  nlohmann::json progress = nlohmann::json::object();
  for (const ActiveTake::Files& files : take.files) {
    const TakeTap& tap = *files.subject->tap;
    progress[tap.subject()] = {{"received_frames", files.raw_frames},
                               {"published_frames", files.filled_frames},
                               {"received_dropped", tap.received_dropped() - files.raw_dropped_before},
                               {"published_dropped", tap.published_dropped() - files.filled_dropped_before}};
  }
  std::lock_guard lock(mutex_);
  progress_ = std::move(progress);
}

void TakeRecorder::write_sidecar(const ActiveTake& take, const std::string& state) const {
  nlohmann::json subjects = nlohmann::json::array();
  for (const ActiveTake::Files& files : take.files) {
    const TakeTap& tap = *files.subject->tap;
    const std::string& stem = files.subject->file_stem;
    subjects.push_back({{"name", tap.subject()},
                        {"subject_file", files.subject_file},
                        {"subject_sha256", files.subject_sha256},
                        {"rate_hz", files.rate_hz},
                        {"raw",
                         {{"c3d", stem + ".raw.c3d"},
                          {"table", stem + ".raw.tsv"},
                          {"labels", tap.received_labels()},
                          {"frames", files.raw_frames},
                          {"dropped", tap.received_dropped() - files.raw_dropped_before}}},
                        {"filled",
                         {{"c3d", stem + ".filled.c3d"},
                          {"table", stem + ".filled.tsv"},
                          {"labels", tap.marker_names()},
                          {"frames", files.filled_frames},
                          {"dropped", tap.published_dropped() - files.filled_dropped_before}}}});
  }
  nlohmann::json sidecar = {{"take", take.name},
                            {"state", state},
                            {"started_utc", iso_utc(take.started)},
                            {"started_by", take.who},
                            {"subjects", std::move(subjects)},
                            {"config", options_.config}};
  if (state != "recording") sidecar["ended_utc"] = iso_utc(std::chrono::system_clock::now());
  std::lock_guard lock(mutex_);
  if (state == "failed") sidecar["error"] = last_error_.empty() ? "disk refused" : last_error_;
  write_json_atomically(take.folder / "take.json", sidecar);
}

std::vector<std::string> TakeRecorder::recover_interrupted() {
  std::vector<std::string> said;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(options_.dir, ec)) {
    const std::filesystem::path sidecar_path = entry.path() / "take.json";
    if (!entry.is_directory() || !std::filesystem::exists(sidecar_path)) continue;
    const std::string take = entry.path().filename().string();
    std::string error;
    std::optional<nlohmann::json> sidecar = read_sidecar(sidecar_path, &error);
    if (!sidecar) {
      said.push_back("take " + take + ": take.json unreadable, left as it is: " + error);
      continue;
    }
    const std::string state = sidecar->value("state", "");
    if (state != "recording" && state != "failed") continue;
    try {
      std::string line = "take " + take + " (" +
                         (state == "failed" ? "stopped by a disk error" : "interrupted") + ") closed";
      for (nlohmann::json& subject : (*sidecar)["subjects"]) {
        const double rate = subject.at("rate_hz").get<double>();
        for (const char* kind : {"raw", "filled"}) {
          nlohmann::json& part = subject.at(kind);
          const std::filesystem::path c3d = entry.path() / part.at("c3d").get<std::string>();
          const std::filesystem::path table = entry.path() / part.at("table").get<std::string>();
          if (!std::filesystem::exists(c3d)) {
            part["frames"] = 0;
            continue;
          }
          part["frames"] =
              recover_c3d_take(c3d.string(), part.at("labels").get<std::vector<std::string>>(), rate);
          if (std::filesystem::exists(table)) part["table_frames"] = recover_frame_table(table.string());
        }
        line +=
            fmt::format("; {}: {} received, {} published ({:.1f} s)", subject.value("name", ""),
                        subject["raw"]["frames"].get<uint64_t>(), subject["filled"]["frames"].get<uint64_t>(),
                        subject["raw"]["frames"].get<double>() / rate);
      }
      (*sidecar)["state"] = "recovered";
      (*sidecar)["recovered_utc"] = iso_utc(std::chrono::system_clock::now());
      if (state == "recording") (*sidecar)["error"] = "the daemon stopped while recording";
      write_json_atomically(sidecar_path, *sidecar);
      said.push_back(line);
    } catch (const std::exception& e) {
      said.push_back("take " + take + ": could not be closed: " + e.what());
    }
  }
  std::lock_guard lock(mutex_);
  recovered_ = said;
  return said;
}

nlohmann::json TakeRecorder::list() const {
  struct Entry {
    std::filesystem::file_time_type time;
    std::filesystem::path path;
  };
  std::vector<Entry> entries;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(options_.dir, ec))
    if (entry.is_directory())
      entries.push_back({std::filesystem::last_write_time(entry.path(), ec), entry.path()});
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.time > b.time; });
  if (entries.size() > kMaxListedTakes) entries.resize(kMaxListedTakes);
  nlohmann::json takes = nlohmann::json::array();
  for (const Entry& entry : entries) {
    std::string error;
    const std::optional<nlohmann::json> sidecar = read_sidecar(entry.path / "take.json", &error);
    nlohmann::json item = {{"take", entry.path.filename().string()}};
    if (!sidecar) {
      item["state"] = "unreadable";
      takes.push_back(std::move(item));
      continue;
    }
    for (const char* key : {"state", "started_utc", "ended_utc", "started_by", "error"})
      if (sidecar->contains(key)) item[key] = (*sidecar)[key];
    item["subjects"] = nlohmann::json::array();
    for (const nlohmann::json& subject : sidecar->value("subjects", nlohmann::json::array()))
      item["subjects"].push_back({{"name", subject.value("name", "")},
                                  {"received_frames", subject["raw"].value("frames", 0)},
                                  {"published_frames", subject["filled"].value("frames", 0)}});
    takes.push_back(std::move(item));
  }
  return {{"folder", options_.dir.string()}, {"takes", std::move(takes)}};
}

nlohmann::json TakeRecorder::health() const {
  std::lock_guard lock(mutex_);
  static constexpr const char* kStates[] = {"idle", "recording", "closing", "failed"};
  nlohmann::json health = {{"folder", options_.dir.string()},
                           {"state", kStates[static_cast<int>(state_)]},
                           {"takes_closed", takes_closed_},
                           {"takes_failed", takes_failed_}};
  if (!take_name_.empty()) {
    health["take"] = take_name_;
    health["started_by"] = take_who_;
    health["started_utc"] = iso_utc(take_started_);
    health["subjects"] = progress_;
  }
  if (!last_error_.empty()) health["error"] = last_error_;
  if (!recovered_.empty()) health["recovered_at_start"] = recovered_;
  return health;
}

}  // namespace skinstream::server
