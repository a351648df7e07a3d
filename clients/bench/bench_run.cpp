// The measured quantities, per frame (every clock is this machine's system clock, so the
// differences need no synchronisation; with a shaped link the namespace shares it too):
//   end to end        = subscriber ready - replay send time of the same frame number
//   daemon processing = publish_time_ns - receive_time_ns (both from the frame header; the
//                       publish time is taken after encoding, as the frame goes to the publishers)
//   ingest            = receive_time_ns - replay send time (the network in, and the daemon's io thread)
//   delivery          = subscriber arrival - publish_time_ns (the hand-off, the subscriber queue
//                       and the network out)
//   since receive     = subscriber arrival - receive_time_ns (processing + delivery)
// so end to end = ingest + processing + delivery (+ decoding, with --decode), frame by frame.
#include "clients/bench/bench_run.h"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <thread>

#include "clients/bench/child_command.h"
#include "clients/bench/hostile_waves.h"
#include "clients/bench/latency_samples.h"
#include "clients/bench/replay_engine.h"
#include "clients/bench/send_times.h"
#include "clients/bench/shaped_link.h"
#include "clients/bench/stall_log.h"
#include "clients/bench/subjects.h"
#include "protocol/files/capture_file.h"
#include "protocol/files/file_error.h"
#include "server/client/control_client.h"
#include "server/client/daemon_process.h"
#include "server/client/process_usage.h"
#include "server/tcp_congestion.h"

namespace skinstream::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

fs::path own_folder() { return fs::read_symlink("/proc/self/exe").parent_path(); }

int64_t wall_clock_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string daemon_arguments(const BenchOptions& o, const std::string& source_option) {
  std::string a = source_option + " --deform-threads " + std::to_string(o.deform_threads) + " --log-level warn";
  for (const std::string& word : daemon_subject_arguments(o.subject, o.subjects)) a += " " + server::shell_word(word);
  if (!o.deform_cpus.empty()) a += " --deform-cpus " + server::shell_word(o.deform_cpus);
  if (o.deform_spin_lead_us >= 0) a += " --deform-spin-lead-us " + std::to_string(o.deform_spin_lead_us);
  if (o.publish_threads >= 0) a += " --publish-threads " + std::to_string(o.publish_threads);
  if (o.subscriber_tcp_congestion) a += " --subscriber-tcp-congestion " + server::shell_word(*o.subscriber_tcp_congestion);
  if (!o.daemon_config.empty())
    a += " --config " + server::shell_word(fs::absolute(o.daemon_config).string());
  return a;
}

// The measurement window opens once every subscriber has its first frame (so a slow link's
// MeshInfo and Model transfers are not counted as frame latency) and lasts options.seconds.
struct Window {
  std::atomic<int> subscribers_ready{0};
  // Frames published in [start_ns, end_ns) are counted (by publish time, so the daemon's own
  // counters read at the two ends agree with what the subscribers count).
  std::atomic<int64_t> start_ns{0};  // 0: not open yet
  std::atomic<int64_t> end_ns{INT64_MAX};
  std::atomic<bool> closed{false};
  std::atomic<bool> recording{false};  // --record-ab: a take is recording
};

// --joiner-multicast's group, joined on `interface`; throws std::runtime_error for a bad GROUP:PORT.
client::MulticastOptions joiner_multicast_options(const BenchOptions& o, const std::string& interface) {
  const size_t colon = o.joiner_multicast.rfind(':');
  const int port = colon == std::string::npos ? 0 : std::atoi(o.joiner_multicast.c_str() + colon + 1);
  if (port <= 0 || port > 65534)
    throw std::runtime_error("--joiner-multicast must be GROUP:PORT (a port below 65535), not " +
                             o.joiner_multicast);
  client::MulticastOptions multicast{o.joiner_multicast.substr(0, colon), static_cast<uint16_t>(port),
                                     interface};
  multicast.offer = o.multicast_offer_mbit > 0;
  return multicast;
}

// `multicast_interface`: a joiner of --joiner-multicast, which joins the group on this address.
void subscribe(const BenchOptions& o, const std::string& host, int port, int index,
               const SendTimes& send_times, Window& window, StallLog& stalls, SubscriberTally& tally,
               const std::string& multicast_interface = "") {
  client::Options options;
  if (!multicast_interface.empty()) options.multicast = joiner_multicast_options(o, multicast_interface);
  options.host = host;
  options.port = static_cast<uint16_t>(port);
  options.encoding = o.encoding;
  options.normals = o.normals;
  options.paced = o.paced;
  options.packed = !o.plain_first_contact;
  options.decode = o.decode;
  options.evaluate = o.decode;
  options.subject = subscriber_subject(index, o.subjects);
  const Clock::time_point connecting = Clock::now();
  client::Subscriber subscriber(options);
  tally.reserve(static_cast<size_t>(o.seconds * 130) + 16);
  const std::string who = "subscriber " + std::to_string(index);
  const int64_t period_ns = 1'000'000'000 / 120;
  client::Frame frame;
  bool counted_ready = false;
  int64_t last_frame = -1, last_arrival = 0;
  uint32_t pipeline_dropped = 0;
  while (!window.closed.load(std::memory_order_relaxed)) {
    if (!subscriber.next(frame, std::chrono::milliseconds(500))) continue;
    if (!counted_ready) {
      counted_ready = true;
      tally.first_frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - connecting).count();
      window.subscribers_ready.fetch_add(1);
    }
    const int64_t start = window.start_ns.load(std::memory_order_relaxed);
    if (start == 0 || frame.publish_time_ns < start || frame.publish_time_ns >= window.end_ns.load(std::memory_order_relaxed)) continue;
    const int64_t now = frame.ready_time_ns;
    const int64_t sent = send_times.find(frame.frame_number);
    const int recording = window.recording.load(std::memory_order_relaxed) ? 1 : 0;
    if (sent > 0) {
      tally.end_to_end.ms.push_back((now - sent) * 1e-6);
      tally.ingest.ms.push_back((frame.receive_time_ns - sent) * 1e-6);
      if (o.record_ab_seconds > 0) tally.end_to_end_by_recording[recording].ms.push_back((now - sent) * 1e-6);
    } else {
      ++tally.unmatched;
    }
    tally.processing.ms.push_back((frame.publish_time_ns - frame.receive_time_ns) * 1e-6);
    if (o.record_ab_seconds > 0)
      tally.processing_by_recording[recording].ms.push_back((frame.publish_time_ns - frame.receive_time_ns) *
                                                            1e-6);
    tally.delivery.ms.push_back((frame.arrival_time_ns - frame.publish_time_ns) * 1e-6);
    tally.since_receive.ms.push_back((frame.arrival_time_ns - frame.receive_time_ns) * 1e-6);
    tally.message_bytes += frame.message_bytes;
    if (static_cast<int64_t>(frame.frame_number) <= last_frame) ++tally.out_of_order;
    last_frame = frame.frame_number;
    if (tally.received++ == 0) {
      tally.dropped_first = frame.subscriber_dropped;
      tally.first_arrival_ns = frame.arrival_time_ns;
    } else {
      // The pipeline's own drops, once (every subscriber sees the same counter).
      if (index == 0 && frame.pipeline_dropped != pipeline_dropped) stalls.add_drop(now, "pipeline", frame.pipeline_dropped - pipeline_dropped);
      const int64_t gap = frame.arrival_time_ns - last_arrival;
      tally.longest_gap_ms = std::max(tally.longest_gap_ms, gap * 1e-6);
      if (gap > 3 * period_ns) stalls.add_gap(last_arrival, who, gap * 1e-6);
      if (frame.subscriber_dropped != tally.dropped_last) stalls.add_drop(now, who, frame.subscriber_dropped - tally.dropped_last);
    }
    tally.dropped_last = frame.subscriber_dropped;
    pipeline_dropped = frame.pipeline_dropped;
    last_arrival = tally.last_arrival_ns = frame.arrival_time_ns;
  }
  tally.model_bytes = subscriber.model_bytes();
}

// The joiners of --join-wave: how long each waited for its first frame (from starting to connect:
// the MeshInfo and Model come first), and what they received once in.
nlohmann::json join_wave_report(const BenchOptions& o, const std::vector<SubscriberTally>& joiners,
                                int64_t window_start_ns, int64_t window_end_ns) {
  Samples first_frame;
  long received = 0, dropped = 0, without_frame = 0;
  std::vector<double> rates;
  const double joined_s = (window_end_ns - window_start_ns) * 1e-9 - o.join_after_seconds;
  for (const SubscriberTally& t : joiners) {
    if (t.first_frame_ms < 0)
      ++without_frame;
    else
      first_frame.ms.push_back(t.first_frame_ms);
    received += t.received;
    dropped += t.dropped();
    if (joined_s > 0) rates.push_back(t.received / joined_s);
  }
  std::sort(rates.begin(), rates.end());
  return {{"joiners", o.join_wave},
          {"joined_after_s", o.join_after_seconds},
          {"first_frame_ms", first_frame.summary()},
          {"joiners_without_a_frame", without_frame},
          {"received", received},
          {"dropped", dropped},
          // Over the time since they started to connect (their wait for the Model included).
          {"frames_per_second_since_joining",
           rates.empty() ? nlohmann::json(nullptr)
                         : nlohmann::json{{"slowest", rates.front()}, {"median", rates[rates.size() / 2]}}}};
}

// --joiner-processes: one joiner as a skinstream-sub process, until it has `frames` frames or
// `limit` passes (then killed). Its summary (the JSON it prints last), or {"error": ...}.
// `receiver_address`: with --joiner-multicast, this host's address on the link to join the group on.
// `go`: its standard input, closed by the bench when the joiners join (it is started before).
nlohmann::json run_joiner_process(const BenchOptions& o, const std::string& address, int port, long frames,
                                  std::chrono::seconds limit, const std::string& receiver_address, int go) {
  std::vector<std::string> argv = {(own_folder() / "skinstream-sub").string(),
                                   address + ":" + std::to_string(port),
                                   "--encoding",
                                   client::to_string(o.encoding),
                                   "--frames",
                                   std::to_string(frames),
                                   "--start-at-stdin-end"};
  if (o.normals) argv.push_back("--normals");
  if (o.paced) argv.push_back("--paced");
  if (o.decode) argv.push_back("--evaluate");
  if (o.plain_first_contact) argv.push_back("--plain-first-contact");
  if (!o.joiner_multicast.empty()) {
    argv.insert(argv.end(), {"--multicast", o.joiner_multicast, "--multicast-interface", receiver_address});
    if (o.multicast_offer_mbit == 0) argv.push_back("--multicast-no-offer");
  }
  CommandResult run;
  try {
    run = run_command(argv, {.nice = o.joiner_nice, .idle = o.joiner_idle, .stdin_fd = go, .limit = limit});
  } catch (const std::runtime_error& e) {
    return {{"error", e.what()}};
  }
  const std::string& text = run.output;
  const size_t json_start = text.find("\n{");
  if (json_start == std::string::npos || run.exit_code != 0) {
    const size_t last_line = text.find_last_of('\n', text.size() > 1 ? text.size() - 2 : 0);
    return {{"error",
             "skinstream-sub " +
                 std::string(run.exit_code >= 0 ? "exited " + std::to_string(run.exit_code) : "was killed") +
                 ": " + text.substr(last_line == std::string::npos ? 0 : last_line + 1)}};
  }
  return nlohmann::json::parse(text.substr(json_start + 1), nullptr, false);
}

// The summaries of the joiner processes: the slowest rate once in, the first frames' wait, drops.
nlohmann::json joiner_processes_report(const std::vector<nlohmann::json>& summaries) {
  std::vector<double> rates, first;
  long dropped = 0, pipeline_dropped = 0, failed = 0, offers_taken = 0, offer_timeouts = 0, frames_lost = 0;
  std::string first_error;
  for (const nlohmann::json& s : summaries) {
    if (!s.is_object() || s.contains("error") || s.value("frames", 0L) < 2) {
      ++failed;
      if (first_error.empty())
        first_error = s.is_object() ? s.value("error", std::string("no frames")) : "no summary";
      continue;
    }
    rates.push_back(s["frames_per_second_after_first"].get<double>());
    first.push_back(s["first_frame_seconds"].get<double>());
    dropped += s["subscriber_dropped_after_first"].get<long>();
    pipeline_dropped = std::max(pipeline_dropped, s["pipeline_dropped"].get<long>());
    if (s.contains("multicast")) {
      offers_taken += s["multicast"]["offers_taken"].get<long>();
      offer_timeouts += s["multicast"]["offer_timeouts"].get<long>();
      frames_lost += s["multicast"]["frames_lost"].get<long>();
    }
  }
  std::sort(rates.begin(), rates.end());
  std::sort(first.begin(), first.end());
  auto at = [](const std::vector<double>& v, double q) {
    return v.empty() ? 0.0 : v[static_cast<size_t>(q * (v.size() - 1))];
  };
  return {
      {"processes", summaries.size()},
      {"failed", failed},
      {"first_error", first_error},
      {"frames_per_second_after_first", {{"slowest", at(rates, 0.0)}, {"median", at(rates, 0.5)}}},
      {"first_frame_seconds", {{"p50", at(first, 0.5)}, {"max", at(first, 1.0)}}},
      {"dropped_for_them_after_their_first_frame", dropped},
      {"dropped_in_pipeline_by_their_last_frame", pipeline_dropped},
      // --joiner-multicast: MeshInfo and the Model from the offer, else over TCP; frames lost on the group.
      {"multicast",
       {{"offers_taken", offers_taken}, {"offer_timeouts", offer_timeouts}, {"frames_lost", frames_lost}}}};
}

// Sleeps until `until`, in short steps, throwing once `stop` is set.
void sleep_until_or_stop(Clock::time_point until, const std::atomic<bool>& stop) {
  while (Clock::now() < until) {
    if (stop.load()) throw std::runtime_error("interrupted");
    std::this_thread::sleep_until(std::min(until, Clock::now() + std::chrono::milliseconds(50)));
  }
}

}  // namespace

nlohmann::json run_bench(const BenchOptions& o, const std::atomic<bool>& stop) {
  const fs::path daemon_path = own_folder() / "skinstreamd";
  if (!fs::exists(daemon_path)) throw std::runtime_error(daemon_path.string() + ": skinstreamd not found next to skinstream-bench");
  const Capture capture = read_capture(o.recording);
  if (capture.frame_count <= 0) throw FileError(o.recording, "holds no frames");
  if (!(capture.rate_hz > 0)) throw FileError(o.recording, "has no frame rate");
  const fs::path work = fs::temp_directory_path() / ("skinstream-bench-" + std::to_string(getpid()));
  fs::create_directories(work);
  struct RemoveWork {
    fs::path path;
    ~RemoveWork() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } remove_work{work};

  // The stage network, when asked for: made first, removed last.
  std::unique_ptr<ShapedLink> link;
  // The hostile peers play hosts 127.0.0.2-9: they reach a daemon on loopback only.
  if (o.hostile_waves && o.link_mbit > 0) throw std::runtime_error("--hostile-waves runs on loopback only, not with --link-mbit");
  if (o.join_wave > 0 && o.join_after_seconds >= o.seconds)
    throw std::runtime_error("--join-after-seconds must be less than --seconds, or the joiners never join");
  if (!o.joiner_multicast.empty() && (o.link_mbit <= 0 || o.encoding != client::Encoding::Parameters))
    throw std::runtime_error(
        "--joiner-multicast needs --link-mbit (multicast does not loop back here) and --encoding parameters");
  if (!o.joiner_multicast.empty())
    joiner_multicast_options(o, "0.0.0.0");  // its GROUP:PORT checked before anything starts
  if (o.link_mbit > 0) link = std::make_unique<ShapedLink>(ShapedLinkOptions{.rate_mbit = o.link_mbit});
  const std::string replay_address = link ? link->host_address() : "127.0.0.1";
  const std::string daemon_address = link ? link->inner_address() : "127.0.0.1";

  // The replay server: looping, its timeline from the daemon's first frame request.
  server::asio::io_context replay_io;
  ReplayEngineOptions replay_options;
  replay_options.protocol = o.protocol;
  replay_options.bind_address = replay_address;
  replay_options.tcp_congestion = o.replay_tcp_congestion;
  replay_options.natnet_timestamp_jitter_us = o.natnet_timestamp_jitter_us;
  replay_options.natnet_clock_hz = o.natnet_clock_hz;
  const ReplayStage stage = replay_stage(capture, o.subjects, o.subject_spacing_mm,
                                         o.vicon_subject_name.empty() ? fs::path(o.recording).stem().string() : o.vicon_subject_name);
  ReplayEngine replay(replay_io, stage.subjects, replay_options);
  StallLog stalls;  // before send_times, which writes to it until the replay stops
  SendTimes send_times;
  replay.set_frame_hook([&send_times](uint32_t frame_number, int64_t send_ns) { send_times.record(frame_number, send_ns); });
  replay.start();
  std::thread replay_thread([&replay_io] {
    auto guard = server::asio::make_work_guard(replay_io);
    replay_io.run();
  });
  // Destroyed before `replay`: the io thread never outlives the server.
  struct ReplayThreadStop {
    server::asio::io_context& io;
    std::thread& thread;
    ~ReplayThreadStop() {
      io.stop();
      if (thread.joinable()) thread.join();
    }
  } replay_thread_stop{replay_io, replay_thread};

  server::DaemonLaunch launch;
  launch.program = daemon_path.string();
  launch.arguments = daemon_arguments(o, replay.daemon_source_option());
  // --record-ab: takes into the work folder, started and stopped with a token of this run's own.
  const std::string control_token =
      "bench-" + std::to_string(getpid()) + "-" + std::to_string(wall_clock_ns());
  if (o.record_ab_seconds > 0) {
    const fs::path token_file = work / "control-token";
    {
      std::ofstream out(token_file);
      out << control_token << "\n";
    }
    fs::permissions(token_file, fs::perms::owner_read | fs::perms::owner_write);
    launch.arguments += " --record-dir " + server::shell_word((work / "takes").string()) +
                        " --control-token-file " + server::shell_word(token_file.string());
  }
  if (!o.joiner_multicast.empty())
    launch.arguments += " --multicast " + server::shell_word(o.joiner_multicast) + " --multicast-interface " +
                        daemon_address + " --multicast-offer-mbit " + std::to_string(o.multicast_offer_mbit);
  launch.bind = daemon_address;
  launch.files_stem = (work / "skinstreamd").string();
  if (link)
    for (const std::string& word : link->inside({})) launch.exec_prefix += server::shell_word(word) + " ";
  server::DaemonProcess daemon(launch);
  daemon.wait_until_streaming(std::chrono::seconds(15));

  // Subscribers connect; the window opens once each has a frame.
  Window window;
  std::vector<SubscriberTally> tallies(o.subscribers);
  std::vector<std::string> errors(o.subscribers);
  std::vector<std::thread> threads;
  for (int s = 0; s < o.subscribers; ++s)
    threads.emplace_back([&, s] {
      try {
        subscribe(o, daemon_address, daemon.sub_port(), s, send_times, window, stalls, tallies[s]);
      } catch (const std::exception& e) {
        errors[s] = e.what();
        window.subscribers_ready.fetch_add(1);  // so the window does not wait for it
      }
    });
  struct JoinSubscribers {
    Window& window;
    std::vector<std::thread>& threads;
    ~JoinSubscribers() {
      window.closed = true;
      for (std::thread& t : threads)
        if (t.joinable()) t.join();
    }
  } join_subscribers{window, threads};
  const auto ready_deadline = Clock::now() + std::chrono::seconds(120);
  const auto connect_started = Clock::now();
  while (window.subscribers_ready.load() < o.subscribers) {
    if (Clock::now() > ready_deadline) throw std::runtime_error("the subscribers did not all get a frame within 120 s");
    if (!daemon.running()) throw std::runtime_error("skinstreamd exited:\n" + daemon.log());
    sleep_until_or_stop(Clock::now() + std::chrono::milliseconds(10), stop);
  }
  const double seconds_to_first_frames = std::chrono::duration<double>(Clock::now() - connect_started).count();
  // The join wave: more subscribers at once, into the running stream.
  std::vector<SubscriberTally> joiner_tallies(static_cast<size_t>(o.join_wave));
  std::vector<std::string> joiner_errors(static_cast<size_t>(o.join_wave));
  std::vector<nlohmann::json> joiner_summaries(static_cast<size_t>(o.join_wave));  // --joiner-processes
  // Their threads are started now and wait: started at the join, 60 threads' stacks and first
  // allocations stalled this whole process (the replay's sends and the watchers) for 55-65 ms.
  std::vector<std::thread> joiners;
  std::atomic<bool> joiners_go{false};
  // --joiner-processes: started now too, each waiting for its standard input to end (a pipe of
  // its own, closed at the join): forking 60 processes from this one at the join stalled its
  // threads as long again.
  std::vector<std::array<int, 2>> go_pipes;
  if (o.joiner_processes)
    for (int j = 0; j < o.join_wave; ++j) {
      std::array<int, 2> p{};
      if (pipe2(p.data(), O_CLOEXEC) != 0)
        throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
      go_pipes.push_back(p);
    }
  const std::function<void(bool)> release_processes = [&go_pipes](bool go) {
    for (std::array<int, 2>& p : go_pipes)
      if (p[1] >= 0) {
        if (!go) (void)!::write(p[1], "q", 1);  // stop without connecting
        close(p[1]);
        p[1] = -1;
      }
  };
  struct ReleaseJoiners {  // (a run that ends before the join: they return at once)
    Window& window;
    std::atomic<bool>& go;
    const std::function<void(bool)>& release_processes;
    ~ReleaseJoiners() {
      window.closed = true;
      release_processes(false);
      go = true;
      go.notify_all();
    }
  };
  JoinSubscribers join_joiners{window, joiners};  // the same guard: joined first, being declared later
  ReleaseJoiners release_joiners{window, joiners_go, release_processes};  // released before they are joined
  for (int j = 0; j < o.join_wave; ++j)
    joiners.emplace_back([&, j] {
      if (o.joiner_nice > 0) setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), o.joiner_nice);
      if (o.joiner_idle) {
        const sched_param none{};
        pthread_setschedparam(pthread_self(), SCHED_IDLE, &none);
      }
      if (o.joiner_processes) {
        const double in_window = o.seconds - o.join_after_seconds;
        joiner_summaries[j] = run_joiner_process(
            o, daemon_address, daemon.sub_port(), std::lround(in_window * 120.0),
            std::chrono::seconds(static_cast<long>(o.seconds) + 30), replay_address, go_pipes[j][0]);
        close(go_pipes[j][0]);
        return;
      }
      joiners_go.wait(false);
      if (window.closed) return;
      try {
        subscribe(o, daemon_address, daemon.sub_port(), o.subscribers + j, send_times, window, stalls,
                  joiner_tallies[j], o.joiner_multicast.empty() ? "" : replay_address);
      } catch (const std::exception& e) {
        joiner_errors[j] = e.what();
      }
    });
  // Let the joins' backlog drain; and the joiner processes load (sixty programs starting stalled
  // this one's threads for 30-70 ms at a time over a second) before the window opens.
  sleep_until_or_stop(
      Clock::now() + std::chrono::milliseconds(o.joiner_processes && o.join_wave > 0 ? 2500 : 500), stop);

  const nlohmann::json health_before = daemon.health();
  const int64_t period_ns = static_cast<int64_t>(1e9 / capture.rate_hz);
  const int64_t window_start_ns = wall_clock_ns();
  stalls.start(window_start_ns);
  send_times.start_counting(period_ns, &stalls);
  const uint64_t sent_before = replay.frames_sent();
  const uint64_t replay_dropped_before = replay.frames_dropped();
  const double cpu_before = server::cpu_seconds(daemon.pid());
  const std::map<std::string, double> thread_cpu_before = server::thread_cpu_seconds(daemon.pid());
  const double own_cpu_before = server::cpu_seconds(getpid());
  window.start_ns = window_start_ns;
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds));

  const Clock::time_point join_at = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                       std::chrono::duration<double>(o.join_after_seconds));
  bool joined = o.join_wave == 0;

  std::optional<HostileWaves> waves;
  if (o.hostile_waves) {
    waves.emplace(HostileWaveOptions{daemon.sub_port(), daemon.http_port(), std::chrono::seconds(o.wave_seconds),
                                     std::chrono::seconds(o.calm_seconds), o.hostile_peers},
                  [pid = daemon.pid()] { return server::resident_kb(pid); });
    waves->start();
  }
  // RSS once a second: the first sample after warm-up against the last.
  std::vector<long> rss_samples;
  nlohmann::json rss_steps = nlohmann::json::array();
  uint64_t buffers_after_1s = 0;  // the daemon's encoded frame buffers: RSS steps when they grow
  // --record-ab: a take on, then off, in turn, through the control API.
  int takes_recorded = 0;
  const auto toggle_recording = [&](bool on) {
    const server::ControlReply reply = server::post_control(daemon_address, daemon.http_port(),
                                                            on ? "/takes" : "/takes/stop", control_token);
    if (reply.status != (on ? 201 : 200))
      throw std::runtime_error("--record-ab: the daemon answered " + std::to_string(reply.status) + " " +
                               reply.body.dump());
    window.recording = on;
    if (on) ++takes_recorded;
  };
  Clock::time_point next_toggle = Clock::now();
  for (auto next = Clock::now() + std::chrono::seconds(1); next < deadline; next += std::chrono::seconds(1)) {
    // (The loop ticks once a second: a toggle due within the next 50 ms is taken now.)
    if (o.record_ab_seconds > 0 && Clock::now() + std::chrono::milliseconds(50) >= next_toggle) {
      // A take must have closed before the next starts: a stop answered 200 closes within a moment.
      if (!window.recording) {
        const nlohmann::json recording = daemon.health()["recording"];
        if (recording.value("state", "") == "idle") toggle_recording(true);
      } else {
        toggle_recording(false);
      }
      next_toggle = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(o.record_ab_seconds));
    }
    if (!joined && join_at < next) {
      sleep_until_or_stop(join_at, stop);
      release_processes(true);
      joiners_go = true;
      joiners_go.notify_all();
      joined = true;
    }
    sleep_until_or_stop(next, stop);
    rss_samples.push_back(server::resident_kb(daemon.pid()));
    // Every step of RSS, with its time on the stall log's clock: a leak climbs steadily, memory
    // touched for the first time (a backlog reaching buffers never used before) steps once.
    if (rss_samples.size() > 1 && rss_samples.back() != rss_samples[rss_samples.size() - 2])
      rss_steps.push_back({{"at_s", (wall_clock_ns() - window_start_ns) * 1e-9}, {"kb", rss_samples.back() - rss_samples[rss_samples.size() - 2]}});
    if (rss_samples.size() == 1) buffers_after_1s = daemon.health().value("frame_buffers_allocated", 0);
  }
  sleep_until_or_stop(deadline, stop);
  if (waves) waves->stop();
  const nlohmann::json recording_health =
      o.record_ab_seconds > 0 ? daemon.health()["recording"] : nlohmann::json();
  if (o.record_ab_seconds > 0 && window.recording) toggle_recording(false);
  const int64_t window_end_ns = wall_clock_ns();
  window.end_ns = window_end_ns;
  const nlohmann::json health = daemon.health();
  const uint64_t sent = replay.frames_sent() - sent_before;
  const uint64_t replay_dropped = replay.frames_dropped() - replay_dropped_before;
  const double cpu = server::cpu_seconds(daemon.pid()) - cpu_before;
  const std::map<std::string, double> thread_cpu_after = server::thread_cpu_seconds(daemon.pid());
  const long peak_rss_kb = server::peak_resident_kb(daemon.pid());
  const double own_cpu = server::cpu_seconds(getpid()) - own_cpu_before;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the window's last frames still on their way
  window.closed = true;
  for (std::thread& t : threads) t.join();
  for (std::thread& t : joiners) t.join();
  const int exit_status = daemon.stop();
  for (const std::string& e : errors)
    if (!e.empty()) throw std::runtime_error("subscriber: " + e);
  for (const std::string& e : joiner_errors)
    if (!e.empty()) throw std::runtime_error("joining subscriber: " + e);
  const std::string shaper = link ? link->shaper_stats() : "";

  // What the daemon warned about during the run (dropped frames say why there), first lines only.
  nlohmann::json daemon_warnings = nlohmann::json::array();
  {
    std::ifstream log(daemon.log_path());
    for (std::string text; std::getline(log, text) && daemon_warnings.size() < 20;)
      if (text.find("[warning]") != std::string::npos || text.find("[error]") != std::string::npos) daemon_warnings.push_back(text);
  }

  // The growth over the run, at a glance: a leak climbs minute after minute, a warm-up does not.
  std::vector<long> every_minute;
  for (size_t i = 0; i < rss_samples.size(); i += 60) every_minute.push_back(rss_samples[i]);
  SubscriberTally all;
  long total_dropped = 0;
  std::vector<double> rates;
  nlohmann::json per_subscriber = nlohmann::json::array();
  const double window_s = (window_end_ns - window_start_ns) * 1e-9;
  std::vector<SubscriberTally> by_subject(static_cast<size_t>(o.subjects));  // subscriber s follows subject s mod N
  for (size_t s = 0; s < tallies.size(); ++s) {
    const SubscriberTally& tally = tallies[s];
    all.add(tally);
    by_subject[s % by_subject.size()].add(tally);
    total_dropped += tally.dropped();
    const double rate = tally.received / window_s;
    rates.push_back(rate);
    per_subscriber.push_back(
        {{"received", tally.received}, {"dropped", tally.dropped()}, {"longest_gap_ms", tally.longest_gap_ms}, {"frames_per_second", rate}});
  }
  std::sort(rates.begin(), rates.end());
  std::vector<nlohmann::json> subject_subscribers;
  for (SubscriberTally& t : by_subject)
    subject_subscribers.push_back({{"received", t.received}, {"end_to_end", t.end_to_end.summary()}, {"daemon_processing", t.processing.summary()}});
  auto delta = [&](const char* key) { return health["frames"][key].get<uint64_t>() - health_before["frames"][key].get<uint64_t>(); };
  const double bytes_per_frame = all.received > 0 ? static_cast<double>(all.message_bytes) / all.received : 0.0;
  nlohmann::json report = {
      {"mode", std::string(to_string(o.protocol)) + " replay (in-process) -> skinstreamd -> subscribers, " +
                   (link ? "over a " + std::to_string(o.link_mbit) + " Mbit/s shaped link"
                         : std::string("on loopback"))},
      {"seconds", o.seconds},
      {"window_seconds", window_s},
      {"subscribers", o.subscribers},
      {"subjects", o.subjects},
      {"encoding", client::to_string(o.encoding)},
      {"protocol", to_string(o.protocol)},
      {"natnet_clock",
       {{"timestamp_jitter_us", o.natnet_timestamp_jitter_us}, {"clock_hz", o.natnet_clock_hz}}},
      {"link_mbit", o.link_mbit},
      {"subscribers_want",
       {{"normals", o.normals},
        {"quantised", o.encoding == client::Encoding::Quantised},
        {"decode", o.decode},
        {"paced", o.paced},
        {"packed_first_contact", !o.plain_first_contact},
        {"joiner_nice", o.joiner_nice},
        {"joiner_idle", o.joiner_idle},
        {"joiner_processes", o.joiner_processes},
        {"joiner_multicast", o.joiner_multicast},
        {"multicast_offer_mbit",
         o.joiner_multicast.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.multicast_offer_mbit)}}},
      {"seconds_until_every_subscriber_had_a_frame", seconds_to_first_frames},
      {"deform_threads", o.deform_threads},
      {"deform", health["deform"]},  // as the daemon applied it: threads, CPUs pinned to, spin lead
      {"publish_threads", health["publish_threads"]},
      // The daemon's subscriber connections ("" = the system's, given next).
      {"subscriber_tcp_congestion", health["subscriber_tcp_congestion"]},
      {"replay_tcp_congestion", o.replay_tcp_congestion},
      {"system_tcp_congestion", server::system_tcp_congestion()},
      {"recording", o.recording},
      {"vertices", health["subject"]["vertices"]},
      {"markers", health["subject"]["markers"]},
      {"bytes_per_frame", bytes_per_frame},
      {"model_bytes", tallies.empty() ? 0 : tallies.front().model_bytes},
      {"subscriber_frames_per_second",
       {{"slowest", rates.front()}, {"median", rates[rates.size() / 2]}, {"fastest", rates.back()}}},
      {"end_to_end", all.end_to_end.summary()},
      {"daemon_processing", all.processing.summary()},
      {"ingest", all.ingest.summary()},      // replay send -> daemon receive
      {"delivery", all.delivery.summary()},  // daemon publish -> subscriber arrival
      // daemon receive -> subscriber arrival (processing + delivery): the daemon's and the
      // link's part, without the load generator's replay
      {"since_receive", all.since_receive.summary()},
      {"replay_sends", send_times.regularity()},  // gaps between the replay's consecutive sends
      // The daemon's own stage histograms (/health's latency_ms) over its whole life, warm-up
      // included: quantiles as bucket upper bounds. Delivery splits into subscriber_queue_wait
      // (published -> the write starts) and subscriber_write (-> the socket took the frame).
      {"daemon_stages_ms", health["latency_ms"]},
      {"frames",
       {{"sent_by_replay", sent},
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
      // Each actor's own threads' CPU and the daemon's figures for it; the threads they share.
      {"per_subject", per_subject_report(o.subjects, thread_cpu_before, thread_cpu_after, health_before,
                                         health, subject_subscribers, window_s)},
      {"hostile", waves ? waves->report() : nlohmann::json(nullptr)},
      {"subscriber_limits", health.value("subscriber_limits", nlohmann::json(nullptr))},
      {"join_pacing",
       health.value("join_pacing", nlohmann::json(nullptr))},  // the joiners' first messages, as paced
      // Gaps over 3 frame periods (the replay's sends, each subscriber's arrivals), drops for a
      // subscriber and drops in the pipeline, in time order: a pause of the whole machine shows
      // at one moment in all.
      {"stalls", stalls.to_json()},
      {"daemon",
       {{"cpu_seconds", cpu},
        {"cpu_share_of_one_core", cpu / window_s},
        {"peak_rss_kb", peak_rss_kb},
        {"rss_kb_after_1s", rss_samples.empty() ? 0 : rss_samples.front()},
        {"rss_kb_at_end", rss_samples.empty() ? 0 : rss_samples.back()},
        {"rss_kb_max_sampled",
         rss_samples.empty() ? 0 : *std::max_element(rss_samples.begin(), rss_samples.end())},
        {"rss_kb_every_60s", every_minute},
        {"rss_steps", rss_steps},  // each change between two 1 s samples: at_s, kb
        {"frame_buffers_after_1s", buffers_after_1s},
        {"frame_buffers_at_end", health.value("frame_buffers_allocated", 0)},
        // Of those, made on the 120 Hz thread because no prepared one was ready: 0 when
        // every subscriber's encoding was prepared on its Hello.
        {"frame_buffers_made_by_pipeline", health.value("frame_buffers_allocated_by_pipeline", 0)},
        // Gap filler rebuilds for a new source rate over the daemon's life (1: the rate became known).
        {"source_rate_changes", health["subjects"][0].value("source_rate_changes", uint64_t{0})},
        {"exit_status", exit_status},
        {"warnings", daemon_warnings}}},
      // This process: the replay server and the subscribers, sharing the machine with the daemon.
      {"load_generator", {{"cpu_seconds", own_cpu}, {"cpu_share_of_one_core", own_cpu / window_s}}}};
  if (link) report["shaped_link"] = nlohmann::json::parse(shaper);
  if (o.join_wave > 0 && o.joiner_processes)
    report["join_wave"] = {{"joiners", o.join_wave},
                           {"joined_after_s", o.join_after_seconds},
                           {"processes", joiner_processes_report(joiner_summaries)}};
  else if (o.join_wave > 0)
    report["join_wave"] = join_wave_report(o, joiner_tallies, window_start_ns, window_end_ns);
  if (o.record_ab_seconds > 0) {
    nlohmann::json halves;
    for (int r = 0; r < 2; ++r)
      halves[r ? "on" : "off"] = {{"end_to_end", all.end_to_end_by_recording[r].summary()},
                                  {"daemon_processing", all.processing_by_recording[r].summary()}};
    const auto ratio = [&](const char* what) {
      const double off = halves["off"][what]["p99_ms"].get<double>(),
                   on = halves["on"][what]["p99_ms"].get<double>();
      return off > 0 ? on / off : 0.0;
    };
    report["record_ab"] = {{"seconds", o.record_ab_seconds},
                           {"takes", takes_recorded},
                           {"off", halves["off"]},
                           {"on", halves["on"]},
                           {"daemon_processing_p99_on_over_off", ratio("daemon_processing")},
                           {"end_to_end_p99_on_over_off", ratio("end_to_end")},
                           {"recording_at_the_end", recording_health}};
  }
  return report;
}

}  // namespace skinstream::bench
