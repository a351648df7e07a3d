// skinstream-bench: end-to-end latency and cost of the real skinstreamd, fed over the network as
// in production. In this process: the Vicon DataStream server engine (server/vicon/vicon_server.h)
// loops the recording on an ephemeral loopback port and notes when each frame number is sent
// (the clock read just before the write, so ingest includes it),
// and N subscribers (one thread each, the blocking client of server/client/) note when each frame
// arrived. The daemon is the real skinstreamd, a child process started with --vicon.
//
//   end to end        = subscriber arrival - replay send time of the same frame number
//   daemon processing = publish_time_ns - receive_time_ns (both from the frame header; the
//                       publish time is taken after encoding, as the frame goes to the publishers)
//   ingest            = receive_time_ns - replay send time (the network in, and the daemon's io thread)
//   delivery          = subscriber arrival - publish_time_ns (the hand-off, the subscriber queue
//                       and the network out)
// so end to end = ingest + processing + delivery, frame by frame; the three say where a tail comes from.
//
// Every clock is the same machine's system clock, so the differences need no synchronisation.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "clients/bench/hostile_waves.h"
#include "clients/bench/stall_log.h"
#include "server/client/health_probe.h"
#include "protocol/capture_file.h"
#include "protocol/file_error.h"
#include "server/client/subscriber_client.h"
#include "server/tcp_congestion.h"
#include "server/vicon/vicon_server.h"

namespace {

using namespace skinstream;
namespace fs = std::filesystem;

struct Samples {
  std::vector<double> ms;
  nlohmann::json summary() {
    std::sort(ms.begin(), ms.end());
    auto at = [&](double q) { return ms.empty() ? 0.0 : ms[std::min(ms.size() - 1, static_cast<size_t>(q * (ms.size() - 1) + 0.5))]; };
    return {{"p50_ms", at(0.5)}, {"p99_ms", at(0.99)}, {"p99_9_ms", at(0.999)}, {"max_ms", ms.empty() ? 0.0 : ms.back()}, {"count", ms.size()}};
  }
};

// What one subscriber thread saw: its own, so the threads share nothing while they run; merged
// after they are joined.
struct SubscriberTally {
  Samples end_to_end, processing, ingest, delivery;  // see the report's keys
  long received = 0, unmatched = 0, out_of_order = 0;
  uint32_t dropped_first = 0, dropped_last = 0;  // the daemon's drop counter for it, first and last frame
  double longest_gap_ms = 0.0;                   // between two consecutive frames' arrivals

  void reserve(size_t frames) {
    for (Samples* s : {&end_to_end, &processing, &ingest, &delivery}) s->ms.reserve(frames);
  }
  uint32_t dropped() const { return dropped_last - dropped_first; }
  // Adds another subscriber's samples and counts (not its drop counter: see dropped()).
  void add(const SubscriberTally& other) {
    auto append = [](Samples& to, const Samples& from) { to.ms.insert(to.ms.end(), from.ms.begin(), from.ms.end()); };
    append(end_to_end, other.end_to_end);
    append(processing, other.processing);
    append(ingest, other.ingest);
    append(delivery, other.delivery);
    received += other.received;
    unmatched += other.unmatched;
    out_of_order += other.out_of_order;
  }
};

// Send times by frame number, written by the replay server's io thread and read by the
// subscriber threads. A ring of the last kSlots frames (34 s at 120 Hz): a frame still in flight
// after that long is reported as unmatched rather than given a wrong send time.
class SendTimes {
 public:
  void record(uint32_t frame_number, int64_t send_ns) {
    std::lock_guard lock(mutex_);
    slots_[frame_number % kSlots] = {frame_number, send_ns};
    // The replay's own regularity: after a stall of this (shared) machine it sends the frames
    // it owes back to back, as a capture system's server would after a hitch; the daemon
    // processes such a burst whole unless it is longer than its mailbox (32 frames).
    if (counting_ && last_send_ns_ > 0) {
      const int64_t gap = send_ns - last_send_ns_;
      max_gap_ns_ = std::max(max_gap_ns_, gap);
      if (gap > 3 * period_ns_) {
        ++gaps_over_3_periods_;
        if (stalls_) stalls_->add_gap(last_send_ns_, "replay", static_cast<double>(gap) / 1e6);
      }
    }
    last_send_ns_ = send_ns;
  }
  // From now on, gaps are counted and those over 3 periods logged to `stalls`.
  void start_counting(int64_t period_ns, bench::StallLog* stalls) {
    std::lock_guard lock(mutex_);
    period_ns_ = period_ns;
    stalls_ = stalls;
    counting_ = true;
  }
  nlohmann::json regularity() const {
    std::lock_guard lock(mutex_);
    return {{"max_gap_ms", static_cast<double>(max_gap_ns_) / 1e6}, {"gaps_over_3_frame_periods", gaps_over_3_periods_}};
  }
  // 0 when the frame number was never sent (or is too old).
  int64_t find(uint32_t frame_number) const {
    std::lock_guard lock(mutex_);
    const Slot& slot = slots_[frame_number % kSlots];
    return slot.frame_number == frame_number ? slot.send_ns : 0;
  }

 private:
  static constexpr uint32_t kSlots = 4096;
  struct Slot {
    uint32_t frame_number = 0;
    int64_t send_ns = 0;
  };
  mutable std::mutex mutex_;
  std::array<Slot, kSlots> slots_{};
  bool counting_ = false;
  bench::StallLog* stalls_ = nullptr;
  int64_t period_ns_ = 0, last_send_ns_ = 0, max_gap_ns_ = 0;
  uint64_t gaps_over_3_periods_ = 0;
};

fs::path own_folder() { return fs::read_symlink("/proc/self/exe").parent_path(); }

pid_t launch(const std::vector<std::string>& arguments, const std::string& log_path) {
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    FILE* log = std::fopen(log_path.c_str(), "w");
    if (log) {
      dup2(fileno(log), STDOUT_FILENO);
      dup2(fileno(log), STDERR_FILENO);
    }
    std::vector<char*> argv;
    for (const std::string& a : arguments) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Waits for the daemon's ports file; fails when the daemon exits first.
nlohmann::json wait_for_ports(const std::string& path, pid_t pid, const std::string& log_path) {
  for (int i = 0; i < 300; ++i) {
    std::ifstream in(path);
    if (in) return nlohmann::json::parse(in);
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) throw std::runtime_error("skinstreamd exited before listening:\n" + file_text(log_path));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  throw std::runtime_error("skinstreamd did not write its ports file within 15 s");
}

// CPU seconds (user + system) and peak RSS (kB) of a running process.
// Resident set now (VmRSS, kB): sampled through the run to show whether memory stays flat.
long resident_kb(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

std::pair<double, long> process_usage(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  double cpu = 0;
  const size_t close = text.rfind(')');
  if (close != std::string::npos) {
    std::istringstream fields(text.substr(close + 2));
    std::string field;
    long utime = 0, stime = 0;
    for (int i = 3; fields >> field; ++i) {  // field 3 is the state
      if (i == 14) utime = std::stol(field);
      if (i == 15) {
        stime = std::stol(field);
        break;
      }
    }
    cpu = static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  }
  long hwm = 0;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) hwm = std::stol(line.substr(6));
  return {cpu, hwm};
}


// Waits until /health says the source is streaming (the daemon has connected to the replay).
void wait_for_streaming(int http_port, pid_t pid, const std::string& log_path) {
  for (int i = 0; i < 300; ++i) {
    if (server::fetch_health(http_port)["source"]["state"] == "streaming") return;
    if (waitpid(pid, nullptr, WNOHANG) == pid) throw std::runtime_error("skinstreamd exited:\n" + file_text(log_path));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  throw std::runtime_error("skinstreamd did not start streaming from the replay server within 15 s:\n" + file_text(log_path));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"skinstream-bench: end-to-end latency and cost of the real skinstreamd fed by a Vicon DataStream replay"};
  double seconds = 10;
  int subscriber_count = 1, deform_threads = 2;
  std::string recording = "replay_data/cmu/85_12.c3d", subject, vicon_subject_name, deform_cpus;
  int deform_spin_lead_us = -1;  // -1: the daemon's default
  int publish_threads = -1;      // -1: the daemon's default
  std::optional<std::string> tcp_congestion;  // unset: the daemon's default
  std::string replay_tcp_congestion = server::ViconServerOptions{}.tcp_congestion;
  bool json = false, normals = false, quantised = false, hostile_waves = false;
  int wave_seconds = 60, calm_seconds = 60;
  app.add_option("--seconds", seconds, "how long to measure")->check(CLI::Range(0.5, 3600.0))->capture_default_str();
  app.add_option("--subscribers", subscriber_count, "subscribers connected in-process, one thread each")->check(CLI::Range(1, 256))->capture_default_str();
  app.add_option("--recording", recording, "capture the Vicon replay server streams, looped")->capture_default_str();
  app.add_option("--subject", subject, "subject file for the recording's performer")->required();
  app.add_option("--deform-threads", deform_threads, "skinstreamd --deform-threads")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--deform-cpus", deform_cpus, "skinstreamd --deform-cpus (default: the daemon's, auto)");
  app.add_option("--deform-spin-lead-us", deform_spin_lead_us, "skinstreamd --deform-spin-lead-us (default: the daemon's)")
      ->check(CLI::Range(0, 1'000'000));
  app.add_option("--publish-threads", publish_threads, "skinstreamd --publish-threads (default: the daemon's)")->check(CLI::Range(0, 16));
  app.add_option("--subscriber-tcp-congestion", tcp_congestion,
                 "skinstreamd --subscriber-tcp-congestion (default: the daemon's, reno; \"\" = the system's)");
  app.add_option("--replay-tcp-congestion", replay_tcp_congestion,
                 "TCP congestion control of the replay server's connection to the daemon (\"\" = the system's)")
      ->capture_default_str();
  app.add_option("--vicon-subject-name", vicon_subject_name, "subject name the replay announces (default: the recording's file name)");
  app.add_flag("--normals", normals, "subscribers ask for normals too");
  app.add_flag("--quantised", quantised, "subscribers ask for the quantised encoding (half the bytes)");
  app.add_flag("--json", json, "print the report as JSON");
  app.add_flag("--hostile-waves", hostile_waves,
               "the soak: hostile peers (stalled, flooding, churning) connect and leave in waves while the subscribers measure");
  app.add_option("--wave-seconds", wave_seconds, "--hostile-waves: how long each wave stays")->check(CLI::Range(1, 3600))->capture_default_str();
  app.add_option("--calm-seconds", calm_seconds, "--hostile-waves: the calm after each wave, at whose end RSS is noted")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const fs::path daemon_path = own_folder() / "skinstreamd";
  const std::string work = (fs::temp_directory_path() / ("skinstream-bench-" + std::to_string(getpid()))).string();
  const std::string ports_path = work + "/ports.json", log_path = work + "/skinstreamd.log";
  pid_t pid = -1;
  server::asio::io_context replay_io;
  std::thread replay_thread;
  auto stop_replay = [&] {
    replay_io.stop();
    if (replay_thread.joinable()) replay_thread.join();
  };
  try {
    if (!fs::exists(daemon_path)) throw std::runtime_error(daemon_path.string() + ": skinstreamd not found next to skinstream-bench");
    const Capture capture = read_capture(recording);
    if (capture.frame_count <= 0) throw FileError(recording, "holds no frames");
    if (!(capture.rate_hz > 0)) throw FileError(recording, "has no frame rate");
    fs::create_directories(work);

    // The replay server: looping, timeline from the daemon's first frame request.
    server::ViconServerOptions replay_options;
    replay_options.bind_address = "127.0.0.1";
    replay_options.port = 0;
    replay_options.loop = true;
    replay_options.tcp_congestion = replay_tcp_congestion;
    replay_options.subject_name = vicon_subject_name.empty() ? fs::path(recording).stem().string() : vicon_subject_name;
    server::ViconServer replay(replay_io, capture, replay_options);
    bench::StallLog stalls;  // before send_times, which writes to it until the replay stops
    SendTimes send_times;
    replay.set_frame_hook([&send_times](uint32_t frame_number, int64_t send_ns) { send_times.record(frame_number, send_ns); });
    replay.start();
    replay_thread = std::thread([&replay_io] {
      auto guard = server::asio::make_work_guard(replay_io);
      replay_io.run();
    });
    // Declared after `replay`, so it is destroyed first: the io thread never outlives the server.
    struct ReplayThreadStop {
      std::function<void()> stop;
      ~ReplayThreadStop() { stop(); }
    } replay_thread_stop{stop_replay};

    std::vector<std::string> daemon_args = {daemon_path.string(), "--subject", subject, "--vicon", "127.0.0.1:" + std::to_string(replay.port()),
                                            "--deform-threads", std::to_string(deform_threads), "--http-port", "0", "--sub-port", "0",
                                            "--bind", "127.0.0.1", "--ports-file", ports_path, "--log-level", "warn"};
    if (!deform_cpus.empty()) daemon_args.insert(daemon_args.end(), {"--deform-cpus", deform_cpus});
    if (deform_spin_lead_us >= 0) daemon_args.insert(daemon_args.end(), {"--deform-spin-lead-us", std::to_string(deform_spin_lead_us)});
    if (publish_threads >= 0) daemon_args.insert(daemon_args.end(), {"--publish-threads", std::to_string(publish_threads)});
    if (tcp_congestion) daemon_args.insert(daemon_args.end(), {"--subscriber-tcp-congestion", *tcp_congestion});
    pid = launch(daemon_args, log_path);
    const nlohmann::json ports = wait_for_ports(ports_path, pid, log_path);
    const int sub_port = ports.at("sub"), http_port = ports.at("http");
    wait_for_streaming(http_port, pid, log_path);
    const nlohmann::json health_before = server::fetch_health(http_port);
    const int64_t period_ns = static_cast<int64_t>(1e9 / capture.rate_hz);
    const int64_t window_start_ns = sub::wall_clock_ns();  // the stall log's and the RSS steps' zero
    stalls.start(window_start_ns);
    send_times.start_counting(period_ns, &stalls);
    const uint64_t sent_before = replay.stats().frame_packets_sent.load();
    const uint64_t replay_dropped_before = replay.stats().frames_dropped.load();
    const double cpu_before = process_usage(pid).first;  // startup (loading the subject) is not counted
    const double own_cpu_before = process_usage(getpid()).first;

    std::vector<SubscriberTally> tallies(subscriber_count);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    const uint32_t wants = (normals ? subscriber::kWantNormals : 0u) | (quantised ? subscriber::kWantQuantised : 0u);
    std::vector<std::thread> threads;
    std::vector<std::string> errors(subscriber_count);
    for (int s = 0; s < subscriber_count; ++s)
      threads.emplace_back([&, s] {
        SubscriberTally& tally = tallies[s];
        try {
          sub::SubscriberClient client("127.0.0.1", std::to_string(sub_port), wants);
          tally.reserve(static_cast<size_t>(seconds * capture.rate_hz * 1.2) + 16);
          int64_t last_frame = -1, last_arrival = 0;
          uint32_t pipeline_dropped = 0;
          const std::string who = "subscriber " + std::to_string(s);
          client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t now) {
            if (type == subscriber::MessageType::Frame) {
              // The numbers only: copying the vertices out is a renderer's work, not the daemon's.
              const subscriber::FrameInfo info = subscriber::decode_frame_info(payload);
              const int64_t sent = send_times.find(info.frame_number);
              if (sent > 0) {
                tally.end_to_end.ms.push_back((now - sent) * 1e-6);
                tally.ingest.ms.push_back((info.receive_time_ns - sent) * 1e-6);
              } else {
                ++tally.unmatched;
              }
              tally.processing.ms.push_back((info.publish_time_ns - info.receive_time_ns) * 1e-6);
              tally.delivery.ms.push_back((now - info.publish_time_ns) * 1e-6);
              if (static_cast<int64_t>(info.frame_number) <= last_frame) ++tally.out_of_order;
              last_frame = info.frame_number;
              if (tally.received++ == 0) {
                tally.dropped_first = info.subscriber_dropped;
              } else {
                // The pipeline's own drops, once (every subscriber sees the same counter).
                if (s == 0 && info.pipeline_dropped != pipeline_dropped)
                  stalls.add_drop(now, "pipeline", info.pipeline_dropped - pipeline_dropped);
                const int64_t gap = now - last_arrival;
                tally.longest_gap_ms = std::max(tally.longest_gap_ms, gap * 1e-6);
                if (gap > 3 * period_ns) stalls.add_gap(last_arrival, who, gap * 1e-6);
                if (info.subscriber_dropped != tally.dropped_last) stalls.add_drop(now, who, info.subscriber_dropped - tally.dropped_last);
              }
              tally.dropped_last = info.subscriber_dropped;
              pipeline_dropped = info.pipeline_dropped;
              last_arrival = now;
            }
            return std::chrono::steady_clock::now() < deadline;
          });
        } catch (const std::exception& e) {
          errors[s] = e.what();
        }
      });
    std::optional<bench::HostileWaves> waves;
    if (hostile_waves) {
      waves.emplace(bench::HostileWaveOptions{sub_port, http_port, std::chrono::seconds(wave_seconds), std::chrono::seconds(calm_seconds)},
                    [pid] { return resident_kb(pid); });
      waves->start();
    }
    // RSS once a second: the first sample after warm-up against the last.
    std::vector<long> rss_samples;
    nlohmann::json rss_steps = nlohmann::json::array();
    uint64_t buffers_after_1s = 0;  // the daemon's encoded frame buffers: RSS steps when they grow
    const auto first_sample = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    for (auto next = first_sample; next < deadline; next += std::chrono::seconds(1)) {
      std::this_thread::sleep_until(next);
      rss_samples.push_back(resident_kb(pid));
      // Every step of RSS, with its time on the stall log's clock: a leak climbs steadily, memory
      // touched for the first time (a backlog reaching buffers never used before) steps once.
      if (rss_samples.size() > 1 && rss_samples.back() != rss_samples[rss_samples.size() - 2])
        rss_steps.push_back({{"at_s", (sub::wall_clock_ns() - window_start_ns) * 1e-9},
                             {"kb", rss_samples.back() - rss_samples[rss_samples.size() - 2]}});
      if (rss_samples.size() == 1) buffers_after_1s = server::fetch_health(http_port).value("frame_buffers_allocated", 0);
    }
    if (waves) waves->stop();
    for (std::thread& t : threads) t.join();
    // The growth over the run, at a glance: a leak climbs minute after minute, a warm-up does not.
    std::vector<long> every_minute;
    for (size_t i = 0; i < rss_samples.size(); i += 60) every_minute.push_back(rss_samples[i]);
    const nlohmann::json health = server::fetch_health(http_port);
    const uint64_t sent = replay.stats().frame_packets_sent.load() - sent_before;
    const uint64_t replay_dropped = replay.stats().frames_dropped.load() - replay_dropped_before;
    const auto [cpu_total, peak_rss_kb] = process_usage(pid);
    const double own_cpu_seconds = process_usage(getpid()).first - own_cpu_before;
    const double cpu_seconds = cpu_total - cpu_before;
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
    pid = -1;
    stop_replay();
    for (const std::string& e : errors)
      if (!e.empty()) throw std::runtime_error("subscriber: " + e);

    // What the daemon warned about during the run (dropped frames say why there), first lines only.
    std::vector<std::string> daemon_warnings;
    {
      std::ifstream log(log_path);
      for (std::string text; std::getline(log, text) && daemon_warnings.size() < 20;)
        if (text.find("[warning]") != std::string::npos || text.find("[error]") != std::string::npos) daemon_warnings.push_back(text);
    }

    SubscriberTally all;
    long total_dropped = 0;
    nlohmann::json per_subscriber = nlohmann::json::array();
    for (const SubscriberTally& tally : tallies) {
      all.add(tally);
      total_dropped += tally.dropped();
      per_subscriber.push_back({{"received", tally.received}, {"dropped", tally.dropped()}, {"longest_gap_ms", tally.longest_gap_ms}});
    }
    auto delta = [&](const char* key) { return health["frames"][key].get<uint64_t>() - health_before["frames"][key].get<uint64_t>(); };
    // CPU: the measured window only; peak RSS: the daemon's whole life.
    const nlohmann::json report = {
        {"mode", "Vicon DataStream replay (in-process, loopback) -> skinstreamd --vicon -> subscribers"},
        {"seconds", seconds},
        {"subscribers", subscriber_count},
        {"subscribers_want", {{"normals", normals}, {"quantised", quantised}}},
        {"deform_threads", deform_threads},
        {"deform", health["deform"]},  // as the daemon applied it: threads, CPUs pinned to, spin lead
        {"publish_threads", health["publish_threads"]},
        // The daemon's subscriber connections ("" = the system's, given next).
        {"subscriber_tcp_congestion", health["subscriber_tcp_congestion"]},
        {"replay_tcp_congestion", replay_tcp_congestion},
        {"system_tcp_congestion", server::system_tcp_congestion()},
        {"recording", recording},
        {"vertices", health["subject"]["vertices"]},
        {"markers", health["subject"]["markers"]},
        {"end_to_end", all.end_to_end.summary()},
        {"daemon_processing", all.processing.summary()},
        {"ingest", all.ingest.summary()},      // replay send -> daemon receive
        {"delivery", all.delivery.summary()},  // daemon publish -> subscriber arrival
        {"replay_sends", send_times.regularity()},  // gaps between the replay's consecutive sends
        // The daemon's own stage histograms (/health's latency_ms) over its whole life, warm-up
        // included: quantiles as bucket upper bounds. Delivery splits into subscriber_queue_wait
        // (published -> the write starts) and subscriber_write (-> the socket took the frame).
        {"daemon_stages_ms", health["latency_ms"]},
        {"frames", {{"sent_by_replay", sent},
                    {"dropped_by_replay", replay_dropped},
                    {"received_by_daemon", delta("received")},
                    {"processed", delta("processed")},
                    {"published", delta("published")},
                    {"dropped_in_pipeline", delta("dropped")},
                    {"dropped_in_pipeline_mailbox_full", delta("dropped_mailbox_full")},
                    {"received_by_subscribers", all.received},
                    {"dropped_for_subscribers", total_dropped},
                    {"out_of_order", all.out_of_order},
                    {"without_send_time", all.unmatched}}},
        {"per_subscriber", per_subscriber},
        {"frames_per_second_per_subscriber", static_cast<double>(all.received) / seconds / subscriber_count},
        {"hostile", waves ? waves->report() : nlohmann::json(nullptr)},
        {"subscriber_limits", health.value("subscriber_limits", nlohmann::json(nullptr))},
        // Gaps over 3 frame periods (the replay's sends, each subscriber's arrivals), drops for a
        // subscriber and drops in the pipeline, in time order: a pause of the whole machine shows
        // at one moment in all.
        {"stalls", stalls.to_json()},
        {"daemon", {{"cpu_seconds", cpu_seconds}, {"cpu_share_of_one_core", cpu_seconds / seconds}, {"peak_rss_kb", peak_rss_kb},
                    {"rss_kb_after_1s", rss_samples.empty() ? 0 : rss_samples.front()},
                    {"rss_kb_at_end", rss_samples.empty() ? 0 : rss_samples.back()},
                    {"rss_kb_max_sampled", rss_samples.empty() ? 0 : *std::max_element(rss_samples.begin(), rss_samples.end())},
                    {"rss_kb_every_60s", every_minute},
                    {"rss_steps", rss_steps},  // each change between two 1 s samples: at_s, kb
                    {"frame_buffers_after_1s", buffers_after_1s},
                    {"frame_buffers_at_end", health.value("frame_buffers_allocated", 0)},
                    // Of those, made on the 120 Hz thread because no prepared one was ready: 0 when
                    // every subscriber's encoding was prepared on its Hello.
                    {"frame_buffers_made_by_pipeline", health.value("frame_buffers_allocated_by_pipeline", 0)},
                    {"exit_status", WIFEXITED(status) ? WEXITSTATUS(status) : -1},
                    {"warnings", daemon_warnings}}},
        // This process: the replay server and the subscribers, sharing the machine with the daemon.
        {"load_generator", {{"cpu_seconds", own_cpu_seconds}, {"cpu_share_of_one_core", own_cpu_seconds / seconds}}}};
    if (json) {
      std::printf("%s\n", report.dump(2).c_str());
    } else {
      auto line = [&](const char* name, const nlohmann::json& s) {
        std::printf("%-20s p50 %.3f ms  p99 %.3f ms  p99.9 %.3f ms  max %.3f ms  (%zu samples)\n", name, s["p50_ms"].get<double>(),
                    s["p99_ms"].get<double>(), s["p99_9_ms"].get<double>(), s["max_ms"].get<double>(), s["count"].get<size_t>());
      };
      std::printf("%s\n", report["mode"].get<std::string>().c_str());
      line("end to end", report["end_to_end"]);
      line("daemon processing", report["daemon_processing"]);
      line("  ingest", report["ingest"]);
      line("  delivery", report["delivery"]);
      for (const char* stage : {"subscriber_queue_wait", "subscriber_write"}) {
        const nlohmann::json& h = report["daemon_stages_ms"][stage];
        std::printf("    %-22s p50 <= %.3f ms  p99 <= %.3f ms  max %.3f ms  (daemon side, %lu samples)\n", stage,
                    h["p50_le"].get<double>(), h["p99_le"].get<double>(), h["max"].get<double>(), h["count"].get<unsigned long>());
      }
      std::printf("frames: %s\n", report["frames"].dump().c_str());
      std::printf("daemon: %.2f s CPU (%.0f%% of one core), peak RSS %ld kB, RSS %ld kB after 1 s and %ld kB at the end\n",
                  cpu_seconds, 100 * cpu_seconds / seconds, peak_rss_kb, rss_samples.empty() ? 0L : rss_samples.front(),
                  rss_samples.empty() ? 0L : rss_samples.back());
      for (const auto& step : report["daemon"]["rss_steps"])
        std::printf("at %.0f s: daemon RSS %+ld kB\n", step["at_s"].get<double>(), step["kb"].get<long>());
      for (const std::string& text : daemon_warnings) std::printf("daemon: %s\n", text.c_str());
      for (const auto& event : report["stalls"]["events"]) {
        if (event.contains("dropped"))
          std::printf("at %.3f s: %s: %u frames dropped%s\n", event["at_s"].get<double>(), event["who"].get<std::string>().c_str(),
                      event["dropped"].get<uint32_t>(), event["who"] == "pipeline" ? "" : " for it");
        else
          std::printf("at %.3f s: %s: nothing for %.1f ms\n", event["at_s"].get<double>(), event["who"].get<std::string>().c_str(),
                      event["gap_ms"].get<double>());
      }
    }
    fs::remove_all(work);
    return 0;
  } catch (const std::exception& e) {
    if (pid > 0) {
      kill(pid, SIGTERM);
      waitpid(pid, nullptr, 0);
    }
    stop_replay();
    std::fprintf(stderr, "skinstream-bench: error: %s\n", e.what());
    return 1;
  }
}
