#include "server/subjects/subject_changes.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "protocol/files/capture_file.h"
#include "protocol/printable_text.h"
#include "server/file_naming.h"
#include "server/record/take_recorder.h"
#include "server/subject_stream.h"
#include "server/subjects/subject_builder.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

// Below the stream's threads, level with the take recorder: a swap's load and check run here.
constexpr int kChangesNice = 10;

// A source subject's name as a route's segment carries it.
bool valid_subject_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(),
                     [](unsigned char c) { return c >= 0x21 && c < 0x7f && c != '/'; });
}

bool under_way(const nlohmann::json& change) {
  if (change.is_null()) return false;
  const std::string state = change.value("state", "");
  return state != "done" && state != "failed";
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

SubjectChanges::SubjectChanges(SubjectChangesOptions options, const std::vector<SubjectStream*>& subjects,
                               Host& host, TakeRecorder* recorder)
    : options_(std::move(options)), host_(host), recorder_(recorder) {
  for (SubjectStream* subject : subjects) {
    auto entry = std::make_shared<Entry>();
    entry->name = subject->name();
    entry->stream = subject;
    entries_.push_back(std::move(entry));
  }
  thread_ = std::thread([this] { run(); });
}

SubjectChanges::~SubjectChanges() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  cancel_.store(true);
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::shared_ptr<SubjectChanges::Entry> SubjectChanges::find(const std::string& name) const {
  for (const auto& entry : entries_)
    if (entry->name == name) return entry;
  return nullptr;
}

ControlAnswer SubjectChanges::begin(Entry& entry, const std::string& kind, const std::string& state,
                                    const std::string& who, nlohmann::json details) {
  std::lock_guard lock(mutex_);
  if (under_way(entry.change))
    return {409,
            {{"error", "subject " + entry.name + ": a " + entry.change.value("kind", "") + " is under way (" +
                           entry.change.value("state", "") + "): wait for it to end"}}};
  details["kind"] = kind;
  details["state"] = state;
  details["who"] = who;
  details["started"] = iso_utc(std::chrono::system_clock::now());
  entry.change = std::move(details);
  entry.change_started = std::chrono::steady_clock::now();
  return {202, entry.change};
}

namespace {

ControlAnswer no_subject(const std::string& name) {
  return {404, {{"error", "no subject " + quoted_text(name) + " here"}}};
}

}  // namespace

ControlAnswer SubjectChanges::calibrate(const std::string& name, const nlohmann::json& request,
                                        const std::string& who) {
  const std::shared_ptr<Entry> entry = find(name);
  if (!entry || !entry->stream) return no_subject(name);
  const nlohmann::json seconds_value = request.value("seconds", nlohmann::json(30));
  if (!seconds_value.is_number() || !(seconds_value.get<double>() >= 1.0) ||
      seconds_value.get<double>() > options_.max_seconds)
    return {400, {{"error", "seconds must be a number of 1-" + std::to_string(options_.max_seconds)}}};
  const nlohmann::json mesh_value = request.value("mesh", nlohmann::json(options_.mesh));
  if (!mesh_value.is_string()) return {400, {{"error", "mesh must be a file's path"}}};
  const std::string mesh = mesh_value.get<std::string>();
  SubjectStream& subject = *entry->stream;
  if (mesh.empty() && subject.has_mesh())
    return {409,
            {{"error", "subject " + name +
                           " is served with a mesh: a calibration needs a body (\"mesh\" in the request, "
                           "or calibration_mesh)"}}};
  if (!mesh.empty() && !std::filesystem::is_regular_file(mesh))
    return {400, {{"error", "mesh " + quoted_text(mesh) + ": no such file"}}};
  const double rate = host_.source_rate_hz() > 0 ? host_.source_rate_hz() : options_.default_rate_hz;
  const int frames = static_cast<int>(std::lround(seconds_value.get<double>() * rate));
  ControlAnswer answer = begin(*entry, "calibration", "recording", who,
                               {{"seconds", seconds_value.get<double>()},
                                {"frames_wanted", frames},
                                {"frames_recorded", 0},
                                {"mesh", mesh}});
  if (answer.status != 202) return answer;
  entry->capture = std::make_unique<CalibrationCapture>(subject.model().marker_names, frames, rate);
  entry->capture_mesh = mesh;
  ++capturing_count_;
  spdlog::info("subject {}: calibration asked by {}: recording {} frames ({} s) of its range of motion", name,
               who, frames, seconds_value.get<double>());
  return answer;
}

ControlAnswer SubjectChanges::load_file(const std::string& name, const nlohmann::json& request,
                                        const std::string& who) {
  const std::shared_ptr<Entry> entry = find(name);
  if (!entry || !entry->stream) return no_subject(name);
  const nlohmann::json file_value = request.value("file", nlohmann::json());
  if (!file_value.is_string() || file_value.get<std::string>().empty())
    return {400, {{"error", "file must be the subject file's path"}}};
  const std::string file = file_value.get<std::string>();
  ControlAnswer answer = begin(*entry, "file", "loading", who, {{"subject_file", file}});
  if (answer.status != 202) return answer;
  spdlog::info("subject {}: subject file {} asked by {}", name, file, who);
  post([this, entry, file] { swap_in(entry, file); });
  return answer;
}

ControlAnswer SubjectChanges::add(const nlohmann::json& request, const std::string& who) {
  const nlohmann::json name_value = request.value("name", nlohmann::json()),
                       file_value = request.value("file", nlohmann::json());
  if (!name_value.is_string() || !valid_subject_name(name_value.get<std::string>()))
    return {400, {{"error", "name must be the source's subject name: 1-64 printable characters, no '/'"}}};
  if (!file_value.is_string() || file_value.get<std::string>().empty())
    return {400, {{"error", "file must be the subject file's path"}}};
  const std::string name = name_value.get<std::string>(), file = file_value.get<std::string>();
  std::shared_ptr<Entry> entry = find(name);
  if (entry && entry->stream)
    return {409, {{"error", "subject " + quoted_text(name) + " is served already"}}};
  if (!entry) {
    entry = std::make_shared<Entry>();
    entry->name = name;
    entries_.push_back(entry);
  }
  ControlAnswer answer = begin(*entry, "add", "loading", who, {{"subject_file", file}});
  if (answer.status != 202) return answer;
  spdlog::info("subject {}: added from {}, asked by {}", name, file, who);
  post([this, entry, file] { add_subject(entry, file); });
  return answer;
}

ControlAnswer SubjectChanges::remove(const std::string& name, const std::string& who) {
  const std::shared_ptr<Entry> entry = find(name);
  if (!entry || !entry->stream) return no_subject(name);
  {
    std::lock_guard lock(mutex_);
    if (under_way(entry->change))
      return {409,
              {{"error", "subject " + name + ": a " + entry->change.value("kind", "") +
                             " is under way: wait for it to end"}}};
  }
  ControlAnswer answer = host_.remove_subject(name, who);
  if (answer.status != 200) return answer;
  std::erase(entries_, entry);
  return answer;
}

ControlAnswer SubjectChanges::state(const std::string& name) const {
  const std::shared_ptr<Entry> entry = find(name);
  if (!entry) return no_subject(name);
  nlohmann::json out = {{"name", name}, {"change", health(name)}};
  if (const SubjectStream* subject = entry->stream) {
    out["file"] = subject->config().file;
    out["markers"] = subject->model().marker_count();
    out["vertices"] = subject->vertex_count();
  }
  return {200, out};
}

ControlAnswer SubjectChanges::list() const {
  nlohmann::json subjects = nlohmann::json::array();
  for (const auto& entry : entries_) subjects.push_back(state(entry->name).body);
  return {200, {{"subjects", subjects}}};
}

nlohmann::json SubjectChanges::health(const std::string& name) const {
  const std::shared_ptr<Entry> entry = find(name);
  if (!entry) return nullptr;
  std::lock_guard lock(mutex_);
  return entry->change;
}

void SubjectChanges::capture_frame(const SubjectStream& subject, const MarkerFrame& frame) {
  std::shared_ptr<Entry> entry;
  for (const auto& e : entries_)
    if (e->stream == &subject) entry = e;
  if (!entry || !entry->capture) return;
  CalibrationCapture& capture = *entry->capture;
  const bool full = capture.add(frame);
  if (!full && capture.frames() % 60 != 0) return;
  const int recorded = capture.frames();
  update(*entry, [&](nlohmann::json& change) {
    change["frames_recorded"] = recorded;
    if (full) change["state"] = "building";
  });
  if (!full) return;
  // The take goes to this object's thread; the capture's memory with it.
  auto take = std::make_shared<Capture>(capture.take());
  entry->capture.reset();
  --capturing_count_;
  post([this, entry, take, mesh = entry->capture_mesh] { build_and_swap(entry, std::move(*take), mesh); });
}

void SubjectChanges::post(std::function<void()> job) {
  {
    std::lock_guard lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
}

void SubjectChanges::run() {
  name_this_thread("subjects");
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kChangesNice);
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (stopping_) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    job();
  }
}

void SubjectChanges::build_and_swap(const std::shared_ptr<Entry>& entry, Capture capture, std::string mesh) {
  const std::filesystem::path base =
      options_.dir /
      (file_stem_of(entry->name) + "-" + utc_text(std::chrono::system_clock::now(), "%Y%m%d-%H%M%S"));
  const std::filesystem::path take = base.string() + ".rom.c3d", built = base.string() + ".sksubj";
  try {
    std::filesystem::create_directories(options_.dir);
    write_capture(capture, take.string());
  } catch (const std::exception& e) {
    return fail(*entry, std::string("cannot write the range of motion: ") + e.what());
  }
  update(*entry, [&](nlohmann::json& change) { change["capture"] = take.string(); });
  spdlog::info("subject {}: calibration: {} frames recorded to {}; building {} at a low priority (nice 10)",
               entry->name, capture.frame_count, take.string(), built.string());
  const SubjectBuildResult result =
      build_subject({options_.builder, take, built, mesh, options_.build_timeout}, cancel_);
  update(*entry, [&](nlohmann::json& change) {
    change["build_seconds"] = result.seconds;
    change["report"] = result.report.string();
  });
  if (!result.ok) return fail(*entry, result.reason);
  swap_in(entry, built.string());
}

void SubjectChanges::swap_in(const std::shared_ptr<Entry>& entry, const std::string& file) {
  SubjectStream& subject = *entry->stream;  // not removed while a change is under way
  const auto start = std::chrono::steady_clock::now();
  update(*entry, [&](nlohmann::json& change) { change["state"] = "loading"; });
  std::shared_ptr<SubjectStream::Replacement> replacement;
  try {
    replacement = subject.prepare_replacement(file);
  } catch (const std::exception& e) {
    return fail(*entry, e.what());
  }
  if (recorder_) {
    const std::vector<std::string> recorded = recorder_->recorded_marker_names(subject.name());
    if (!recorded.empty() && recorded != SubjectStream::model_of(*replacement).marker_names)
      return fail(*entry, "takes record subject " + subject.name() + " with its " +
                              std::to_string(recorded.size()) + " markers, and " + file +
                              " has other markers (" +
                              std::to_string(SubjectStream::model_of(*replacement).marker_count()) +
                              "): restart the daemon to record it");
  }
  const double load_seconds = seconds_since(start);
  update(*entry, [&](nlohmann::json& change) { change["state"] = "swapping"; });
  const auto switch_start = std::chrono::steady_clock::now();
  if (!host_.run_on_io_thread([&] {
        subject.switch_input(*replacement);
        host_.retarget(subject);
      }))
    return fail(*entry, "the daemon is stopping");
  subject.complete_replacement(replacement);
  if (recorder_) recorder_->set_subject_file(subject.name(), file);
  const double swap_ms = 1000.0 * seconds_since(switch_start);
  update(*entry, [&](nlohmann::json& change) {
    change["state"] = "done";
    change["subject_file"] = file;
    change["load_seconds"] = load_seconds;
    change["swap_ms"] = swap_ms;
    change["markers"] = SubjectStream::model_of(*replacement).marker_count();
    change["vertices"] = subject.vertex_count();
    change["seconds_in_all"] = seconds_since(entry->change_started);
    change["finished"] = iso_utc(std::chrono::system_clock::now());
  });
  spdlog::info(
      "subject {}: now served from {} (loaded in {:.2f} s, swapped between two frames in {:.1f} ms); its "
      "subscribers "
      "were sent the new model",
      subject.name(), file, load_seconds, swap_ms);
}

void SubjectChanges::add_subject(const std::shared_ptr<Entry>& entry, const std::string& file) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<SubjectStream> made;
  try {
    made = host_.make_subject(entry->name, file);
  } catch (const std::exception& e) {
    return fail(*entry, e.what());
  }
  SubjectStream* subject = made.get();
  const double load_seconds = seconds_since(start);
  if (!host_.run_on_io_thread([&] {
        host_.insert_subject(std::move(made));
        entry->stream = subject;
      }))
    return fail(*entry, "the daemon is stopping");
  update(*entry, [&](nlohmann::json& change) {
    change["state"] = "done";
    change["load_seconds"] = load_seconds;
    change["markers"] = subject->model().marker_count();
    change["vertices"] = subject->vertex_count();
    change["finished"] = iso_utc(std::chrono::system_clock::now());
  });
  spdlog::info("subject {}: added from {} ({} markers, {} vertices, loaded in {:.2f} s)", entry->name, file,
               subject->model().marker_count(), subject->vertex_count(), load_seconds);
}

void SubjectChanges::update(Entry& entry, const std::function<void(nlohmann::json&)>& edit) {
  std::lock_guard lock(mutex_);
  if (entry.change.is_object()) edit(entry.change);
}

void SubjectChanges::fail(Entry& entry, const std::string& reason) {
  std::string kind;
  update(entry, [&](nlohmann::json& change) {
    change["state"] = "failed";
    change["reason"] = reason;
    change["finished"] = iso_utc(std::chrono::system_clock::now());
    kind = change.value("kind", "change");
  });
  spdlog::error("subject {}: {} failed, the subjects served stay as they were: {}", entry.name, kind, reason);
}

}  // namespace skinstream::server
