#include "server/subjects/subject_changes.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <ctime>

#include "protocol/files/capture_file.h"
#include "protocol/printable_text.h"
#include "server/record/take_recorder.h"
#include "server/subject_stream.h"
#include "server/subjects/subject_builder.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

// Below the stream's threads, above the recorder's (nice 10 too: a swap waits for it).
constexpr int kChangesNice = 10;

std::string utc_now(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[64];
  std::strftime(text, sizeof text, format, &tm);
  return text;
}

// A subject's name made safe for a file name.
std::string file_stem_of(const std::string& name) {
  std::string out;
  for (const char c : name)
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out.empty() ? "subject" : out;
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

SubjectChanges::SubjectChanges(SubjectChangesOptions options, std::vector<SubjectStream*> subjects,
                               Host& host, TakeRecorder* recorder)
    : options_(std::move(options)),
      subjects_(std::move(subjects)),
      host_(host),
      recorder_(recorder),
      captures_(subjects_.size()),
      capture_meshes_(subjects_.size()),
      changes_(subjects_.size()) {
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

int SubjectChanges::index_of(const std::string& name) const {
  for (size_t k = 0; k < subjects_.size(); ++k)
    if (subjects_[k]->name() == name) return static_cast<int>(k);
  return -1;
}

ControlAnswer SubjectChanges::begin(int index, const std::string& kind, const std::string& state,
                                    const std::string& who, nlohmann::json details) {
  std::lock_guard lock(mutex_);
  nlohmann::json& change = changes_[static_cast<size_t>(index)];
  if (under_way(change))
    return {409,
            {{"error", "subject " + subjects_[static_cast<size_t>(index)]->name() + ": a " +
                           change.value("kind", "") + " is under way (" + change.value("state", "") +
                           "): wait for it to end"}}};
  details["kind"] = kind;
  details["state"] = state;
  details["who"] = who;
  details["started"] = utc_now("%Y-%m-%dT%H:%M:%SZ");
  details["started_steady_ns"] = std::chrono::steady_clock::now().time_since_epoch().count();
  change = std::move(details);
  return {202, change};
}

ControlAnswer SubjectChanges::calibrate(const std::string& name, const nlohmann::json& request,
                                        const std::string& who) {
  const int index = index_of(name);
  if (index < 0) return {404, {{"error", "no subject " + quoted_text(name) + " here"}}};
  const nlohmann::json seconds_value = request.value("seconds", nlohmann::json(30));
  if (!seconds_value.is_number() || !(seconds_value.get<double>() >= 1.0) ||
      seconds_value.get<double>() > options_.max_seconds)
    return {400, {{"error", "seconds must be a number of 1-" + std::to_string(options_.max_seconds)}}};
  const nlohmann::json mesh_value = request.value("mesh", nlohmann::json(options_.mesh));
  if (!mesh_value.is_string()) return {400, {{"error", "mesh must be a file's path"}}};
  const std::string mesh = mesh_value.get<std::string>();
  SubjectStream& subject = *subjects_[static_cast<size_t>(index)];
  if (mesh.empty() && subject.has_mesh())
    return {409,
            {{"error", "subject " + name +
                           " is served with a mesh: a calibration needs a body (\"mesh\" in the request, "
                           "or calibration_mesh)"}}};
  if (!mesh.empty() && !std::filesystem::is_regular_file(mesh))
    return {400, {{"error", "mesh " + quoted_text(mesh) + ": no such file"}}};
  const double rate = host_.source_rate_hz() > 0 ? host_.source_rate_hz() : options_.default_rate_hz;
  const int frames = static_cast<int>(std::lround(seconds_value.get<double>() * rate));
  ControlAnswer answer = begin(index, "calibration", "recording", who,
                               {{"seconds", seconds_value.get<double>()},
                                {"frames_wanted", frames},
                                {"frames_recorded", 0},
                                {"mesh", mesh}});
  if (answer.status != 202) return answer;
  captures_[static_cast<size_t>(index)] =
      std::make_unique<CalibrationCapture>(subject.model().marker_names, frames, rate);
  capture_meshes_[static_cast<size_t>(index)] = mesh;
  ++capturing_count_;
  spdlog::info("subject {}: calibration asked by {}: recording {} frames ({} s) of its range of motion", name,
               who, frames, seconds_value.get<double>());
  return answer;
}

ControlAnswer SubjectChanges::load_file(const std::string& name, const nlohmann::json& request,
                                        const std::string& who) {
  const int index = index_of(name);
  if (index < 0) return {404, {{"error", "no subject " + quoted_text(name) + " here"}}};
  const nlohmann::json file_value = request.value("file", nlohmann::json());
  if (!file_value.is_string() || file_value.get<std::string>().empty())
    return {400, {{"error", "file must be the subject file's path"}}};
  const std::string file = file_value.get<std::string>();
  ControlAnswer answer = begin(index, "file", "loading", who, {{"subject_file", file}});
  if (answer.status != 202) return answer;
  spdlog::info("subject {}: subject file {} asked by {}", name, file, who);
  post([this, index, file] { swap_in(index, file); });
  return answer;
}

ControlAnswer SubjectChanges::state(const std::string& name) const {
  const int index = index_of(name);
  if (index < 0) return {404, {{"error", "no subject " + quoted_text(name) + " here"}}};
  const SubjectStream& subject = *subjects_[static_cast<size_t>(index)];
  return {200,
          {{"name", name},
           {"file", subject.config().file},
           {"markers", subject.model().marker_count()},
           {"vertices", subject.vertex_count()},
           {"change", health(index)}}};
}

ControlAnswer SubjectChanges::list() const {
  nlohmann::json subjects = nlohmann::json::array();
  for (const SubjectStream* s : subjects_) subjects.push_back(state(s->name()).body);
  return {200, {{"subjects", subjects}}};
}

nlohmann::json SubjectChanges::health(int index) const {
  std::lock_guard lock(mutex_);
  nlohmann::json change = changes_[static_cast<size_t>(index)];
  if (change.is_object()) change.erase("started_steady_ns");
  return change;
}

void SubjectChanges::capture_frame(int index, const MarkerFrame& frame) {
  std::unique_ptr<CalibrationCapture>& capture = captures_[static_cast<size_t>(index)];
  if (!capture) return;
  const bool full = capture->add(frame);
  if (!full && capture->frames() % 60 != 0) return;
  const int recorded = capture->frames();
  update(index, [&](nlohmann::json& change) {
    change["frames_recorded"] = recorded;
    if (full) change["state"] = "building";
  });
  if (!full) return;
  // The take goes to this object's thread; the capture's memory with it.
  auto take = std::make_shared<Capture>(capture->take());
  capture.reset();
  --capturing_count_;
  post([this, index, take, mesh = capture_meshes_[static_cast<size_t>(index)]] {
    build_and_swap(index, std::move(*take), mesh);
  });
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

void SubjectChanges::build_and_swap(int index, Capture capture, std::string mesh) {
  const std::string name = subjects_[static_cast<size_t>(index)]->name();
  const std::filesystem::path base = options_.dir / (file_stem_of(name) + "-" + utc_now("%Y%m%d-%H%M%S"));
  const std::filesystem::path take = base.string() + ".rom.c3d", built = base.string() + ".sksubj";
  try {
    std::filesystem::create_directories(options_.dir);
    write_capture(capture, take.string());
  } catch (const std::exception& e) {
    return fail(index, std::string("cannot write the range of motion: ") + e.what());
  }
  update(index, [&](nlohmann::json& change) { change["capture"] = take.string(); });
  spdlog::info("subject {}: calibration: {} frames recorded to {}; building {} at the lowest priority", name,
               capture.frame_count, take.string(), built.string());
  const SubjectBuildResult result =
      build_subject({options_.builder, take, built, mesh, options_.build_timeout}, cancel_);
  update(index, [&](nlohmann::json& change) {
    change["build_seconds"] = result.seconds;
    change["report"] = result.report.string();
  });
  if (!result.ok) return fail(index, result.reason);
  swap_in(index, built.string());
}

void SubjectChanges::swap_in(int index, const std::string& file) {
  SubjectStream& subject = *subjects_[static_cast<size_t>(index)];
  const auto start = std::chrono::steady_clock::now();
  update(index, [&](nlohmann::json& change) { change["state"] = "loading"; });
  std::shared_ptr<SubjectStream::Replacement> replacement;
  try {
    replacement = subject.prepare_replacement(file);
  } catch (const std::exception& e) {
    return fail(index, e.what());
  }
  if (recorder_) {
    const std::vector<std::string> recorded = recorder_->recorded_marker_names(subject.name());
    if (!recorded.empty() && recorded != SubjectStream::model_of(*replacement).marker_names)
      return fail(index, "takes record subject " + subject.name() + " with its " +
                             std::to_string(recorded.size()) + " markers, and " + file +
                             " has other markers (" +
                             std::to_string(SubjectStream::model_of(*replacement).marker_count()) +
                             "): restart the daemon to record it");
  }
  const double load_seconds = seconds_since(start);
  update(index, [&](nlohmann::json& change) { change["state"] = "swapping"; });
  const auto switch_start = std::chrono::steady_clock::now();
  if (!host_.run_on_io_thread([&] {
        subject.switch_input(*replacement);
        host_.retarget(index);
      }))
    return fail(index, "the daemon is stopping");
  subject.complete_replacement(replacement);
  if (recorder_) recorder_->set_subject_file(subject.name(), file);
  const double swap_ms = 1000.0 * seconds_since(switch_start);
  update(index, [&](nlohmann::json& change) {
    change["state"] = "done";
    change["subject_file"] = file;
    change["load_seconds"] = load_seconds;
    change["swap_ms"] = swap_ms;
    change["markers"] = SubjectStream::model_of(*replacement).marker_count();
    change["vertices"] = subject.vertex_count();
    change["seconds_in_all"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch() -
                                      std::chrono::nanoseconds(change.value("started_steady_ns", int64_t{0})))
            .count();
    change["finished"] = utc_now("%Y-%m-%dT%H:%M:%SZ");
  });
  spdlog::info(
      "subject {}: now served from {} (loaded in {:.2f} s, swapped between two frames in {:.1f} ms); its "
      "subscribers "
      "were sent the new model",
      subject.name(), file, load_seconds, swap_ms);
}

void SubjectChanges::update(int index, const std::function<void(nlohmann::json&)>& edit) {
  std::lock_guard lock(mutex_);
  nlohmann::json& change = changes_[static_cast<size_t>(index)];
  if (change.is_object()) edit(change);
}

void SubjectChanges::fail(int index, const std::string& reason) {
  update(index, [&](nlohmann::json& change) {
    change["state"] = "failed";
    change["reason"] = reason;
    change["finished"] = utc_now("%Y-%m-%dT%H:%M:%SZ");
  });
  spdlog::error("subject {}: {} failed, the subject served stays as it was: {}",
                subjects_[static_cast<size_t>(index)]->name(), health(index).value("kind", "change"), reason);
}

}  // namespace skinstream::server
