// skinstream-bench, the real program: a replay server, the real skinstreamd and subscribers on
// loopback for a few seconds, and the report it prints checked for consistency; bad paths fail.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>

#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

const std::string kDemo = SKINSTREAM_DEMO_DIR;

std::string bench(const std::string& arguments) { return std::string(SKINSTREAM_BENCH) + " " + arguments; }

TEST(BenchProgram, ShortRunReportsEveryFrameItCounted) {
  constexpr int kSubscribers = 2;
  const test::ProgramRun r = test::run_program(
      bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo + "/live.c3d --seconds 3 --subscribers " +
            std::to_string(kSubscribers) + " --json"),
      /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto& frames = j["frames"];
  // The replay keeps the take's 120 Hz schedule: 3 s of it, give or take the window's ends.
  EXPECT_GT(frames["sent_by_replay"].get<int>(), 300);
  EXPECT_LT(frames["sent_by_replay"].get<int>(), 400);
  EXPECT_GT(frames["processed"].get<int>(), 0);
  EXPECT_EQ(frames["out_of_order"], 0);

  // The per-subscriber rows add up to the totals, and no subscriber is counted a frame the
  // daemon did not publish in the window (the subscribers connect after it opens and are
  // joined before it closes).
  const auto& per = j["per_subscriber"];
  ASSERT_EQ(per.size(), static_cast<size_t>(kSubscribers));
  long received = 0, dropped = 0;
  for (const auto& s : per) {
    EXPECT_GT(s["received"].get<long>(), 0);
    EXPECT_LE(s["received"].get<long>() + s["dropped"].get<long>(), frames["published"].get<long>());
    EXPECT_GT(s["longest_gap_ms"].get<double>(), 0.0);
    received += s["received"].get<long>();
    dropped += s["dropped"].get<long>();
  }
  EXPECT_EQ(received, frames["received_by_subscribers"].get<long>());
  EXPECT_EQ(dropped, frames["dropped_for_subscribers"].get<long>());

  // Every received frame is timed, end to end and in the daemon.
  EXPECT_EQ(j["end_to_end"]["count"].get<long>(), received - frames["without_send_time"].get<long>());
  EXPECT_EQ(j["daemon_processing"]["count"].get<long>(), received);
  for (const char* key : {"end_to_end", "daemon_processing", "ingest", "delivery", "since_receive"}) {
    SCOPED_TRACE(key);
    const auto& s = j[key];
    EXPECT_GT(s["p50_ms"].get<double>(), 0.0);
    EXPECT_LE(s["p50_ms"].get<double>(), s["p99_ms"].get<double>());
    EXPECT_LE(s["p99_ms"].get<double>(), s["max_ms"].get<double>());
  }

  // The daemon's delivery split (the histograms also hold the warm-up before the window). Every
  // frame a subscriber received had its write started; all but perhaps each subscriber's last
  // have had the write's completion run too (it may still be queued on a publish thread when
  // the bench asks /health).
  EXPECT_GE(j["daemon_stages_ms"]["subscriber_queue_wait"]["count"].get<long>(), received);
  EXPECT_GE(j["daemon_stages_ms"]["subscriber_write"]["count"].get<long>(), received - kSubscribers);
  for (const char* stage : {"subscriber_queue_wait", "subscriber_write"}) {
    SCOPED_TRACE(stage);
    const auto& h = j["daemon_stages_ms"][stage];
    EXPECT_LE(h["p50_le"].get<double>(), h["p99_le"].get<double>());
    EXPECT_LE(h["p99_le"].get<double>(), h["max"].get<double>());
    EXPECT_GT(h["max"].get<double>(), 0.0);
  }

  // Stalls: within the window, from the replay, the pipeline or one of the subscribers.
  for (const auto& e : j["stalls"]["events"]) {
    EXPECT_GE(e["at_s"].get<double>(), 0.0);
    EXPECT_LT(e["at_s"].get<double>(), 4.0);
    const std::string who = e["who"];
    EXPECT_TRUE(who == "replay" || who == "pipeline" || who == "subscriber 0" || who == "subscriber 1") << who;
    EXPECT_TRUE(e.contains("gap_ms") != e.contains("dropped")) << e.dump();
  }
  // RSS steps: within the window, and together the whole change from the first sample to the last.
  long stepped = 0;
  for (const auto& step : j["daemon"]["rss_steps"]) {
    EXPECT_GT(step["at_s"].get<double>(), 1.0);  // the first sample is taken 1 s in
    EXPECT_LT(step["at_s"].get<double>(), 4.0);
    EXPECT_NE(step["kb"].get<long>(), 0);
    stepped += step["kb"].get<long>();
  }
  EXPECT_EQ(stepped, j["daemon"]["rss_kb_at_end"].get<long>() - j["daemon"]["rss_kb_after_1s"].get<long>());
  EXPECT_EQ(j["daemon"]["exit_status"], 0);  // SIGTERM stops it cleanly
}

// Parameters on the wire: the Model once, then a few kB a frame, far below the float buffer.
TEST(BenchProgram, ParameterSubscribersReportTheModelAndBytesPerFrame) {
  const test::ProgramRun r = test::run_program(
      bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo + "/live.c3d --seconds 2 --subscribers 2 --encoding parameters --json"),
      /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["encoding"], "parameters");
  EXPECT_GT(j["model_bytes"].get<long>(), 0);
  const double bytes = j["bytes_per_frame"].get<double>();
  EXPECT_GT(bytes, 0.0);
  EXPECT_LT(bytes, 12.0 * j["vertices"].get<double>() / 10);  // a tenth of the float positions at most
  const auto& rates = j["subscriber_frames_per_second"];
  EXPECT_LE(rates["slowest"].get<double>(), rates["fastest"].get<double>());
  EXPECT_GT(rates["slowest"].get<double>(), 0.0);
}

// --join-wave: the joiners connect into the running stream and are reported apart from the
// watchers, each with the wait for its first frame; the watchers' figures stay the report's.
TEST(BenchProgram, AJoinWaveIsReportedApartFromTheWatchers) {
  const test::ProgramRun r =
      test::run_program(bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                              "/live.c3d --seconds 3 --subscribers 2 --encoding parameters "
                              "--join-wave 3 --join-after-seconds 1 --json"),
                        /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["per_subscriber"].size(), 2u);  // the watchers alone
  const auto& wave = j["join_wave"];
  EXPECT_EQ(wave["joiners"], 3);
  EXPECT_EQ(wave["joiners_without_a_frame"], 0);
  EXPECT_EQ(wave["first_frame_ms"]["count"], 3);
  EXPECT_GT(wave["first_frame_ms"]["max_ms"].get<double>(), 0.0);
  EXPECT_GT(wave["received"].get<long>(), 0);
  // Joined a second into a three-second window: fewer frames than a watcher's.
  EXPECT_LT(wave["received"].get<long>() / 3, j["per_subscriber"][0]["received"].get<long>());

  const test::ProgramRun late =
      test::run_program(bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                              "/live.c3d --seconds 2 --join-wave 3 --join-after-seconds 5"));
  EXPECT_NE(late.exit_code, 0);
  EXPECT_NE(late.output.find("--join-after-seconds must be less than --seconds"), std::string::npos)
      << late.output;
}

// --joiner-processes: each joiner is a skinstream-sub process, started before the window and let
// go at the join (here under SCHED_IDLE); their summaries are gathered.
TEST(BenchProgram, JoinerProcessesReportTheirOwnSummaries) {
  const test::ProgramRun r =
      test::run_program(bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                              "/live.c3d --seconds 3 --subscribers 1 --encoding parameters "
                              "--join-wave 2 --join-after-seconds 1 --joiner-processes --joiner-idle --json"),
                        /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto& processes = j["join_wave"]["processes"];
  EXPECT_EQ(processes["processes"], 2);
  EXPECT_EQ(processes["failed"], 0) << processes["first_error"];
  EXPECT_GT(processes["first_frame_seconds"]["max"].get<double>(), 0.0);
  EXPECT_GT(processes["frames_per_second_after_first"]["slowest"].get<double>(), 10.0);
  EXPECT_TRUE(j["subscribers_want"]["joiner_processes"].get<bool>());
  EXPECT_TRUE(j["subscribers_want"]["joiner_idle"].get<bool>());
}

// Recording A/B in one run: takes start and stop through the control API, and the figures are
// split by whether one was recording; every frame counted falls in one half.
TEST(BenchProgram, RecordAbSplitsTheFiguresByRecordingOnAndOff) {
  const test::ProgramRun r =
      test::run_program(bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                              "/live.c3d --seconds 5 --subscribers 2 --record-ab 1 --json"),
                        /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto& ab = j["record_ab"];
  EXPECT_GE(ab["takes"].get<int>(), 1);
  const long on = ab["on"]["daemon_processing"]["count"].get<long>(),
             off = ab["off"]["daemon_processing"]["count"].get<long>();
  EXPECT_GT(on, 0);
  EXPECT_GT(off, 0);
  EXPECT_EQ(on + off, j["daemon_processing"]["count"].get<long>());
  EXPECT_GT(ab["daemon_processing_p99_on_over_off"].get<double>(), 0.0);
  EXPECT_GE(ab["recording_at_the_end"]["takes_closed"].get<int>() +
                (ab["recording_at_the_end"]["state"] == "recording"),
            ab["takes"].get<int>());
}

// The other two capture systems drive the daemon too, and their frames are timed end to end
// (the replay's send time found by frame number for every frame but the window's edges).
TEST(BenchProgram, QtmAndNatNetSourcesAreTimedEndToEnd) {
  for (const std::string protocol : {"qtm", "natnet"}) {
    SCOPED_TRACE(protocol);
    const test::ProgramRun r = test::run_program(
        bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo + "/live.c3d --seconds 2 --protocol " + protocol + " --json"),
        /*stderr_too=*/false);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto j = nlohmann::json::parse(r.output);
    EXPECT_EQ(j["protocol"], protocol);
    const long received = j["frames"]["received_by_subscribers"].get<long>();
    EXPECT_GT(received, 100);
    EXPECT_LE(j["frames"]["without_send_time"].get<long>(), 2);
    EXPECT_EQ(j["end_to_end"]["count"].get<long>(), received - j["frames"]["without_send_time"].get<long>());
    EXPECT_GT(j["frames"]["sent_by_replay"].get<long>(), 200);
  }
}

bool is_root() { return geteuid() == 0; }

// The bench's own namespaces (skbench<pid>); ctest runs these tests alone (RUN_SERIAL), so no
// other run's namespace comes or goes meanwhile.
std::string network_namespaces() { return test::run_program("ip netns list | grep '^skbench' || true").output; }

// The shaped link: the daemon in a namespace of its own behind tc, reached through it, and
// nothing of it left afterwards. Root only (CI runs as root); elsewhere the next test applies.
TEST(BenchProgram, ShapedLinkCarriesTheStreamAndIsRemovedAfterwards) {
  if (!is_root()) GTEST_SKIP() << "needs root to make a network namespace";
  const std::string before = network_namespaces();
  const test::ProgramRun r = test::run_program(
      bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo + "/live.c3d --seconds 2 --encoding parameters --link-mbit 100 --json"),
      /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["link_mbit"], 100);
  EXPECT_GT(j["frames"]["received_by_subscribers"].get<long>(), 0);
  // tc's own counters: the frames crossed the shaper, both ways.
  long sent_out = 0, sent_in = 0;
  for (const auto& q : j["shaped_link"]["to_namespace"]) sent_in += q.value("bytes", 0L);
  for (const auto& q : j["shaped_link"]["from_namespace"]) sent_out += q.value("bytes", 0L);
  EXPECT_GT(sent_out, j["frames"]["received_by_subscribers"].get<long>() * 1000);  // a parameter frame is kilobytes
  EXPECT_GT(sent_in, 0);
  EXPECT_EQ(network_namespaces(), before);
}

// Ctrl-C in the middle of a run: the bench stops the daemon and removes the namespace on its way out.
TEST(BenchProgram, InterruptedRunLeavesNoNamespaceBehind) {
  if (!is_root()) GTEST_SKIP() << "needs root to make a network namespace";
  const std::string before = network_namespaces();
  const test::ProgramRun r = test::run_program("timeout --preserve-status -s INT 6 " +
                                               bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                                                     "/live.c3d --seconds 60 --encoding parameters --link-mbit 100"));
  EXPECT_EQ(r.exit_code, 130) << r.output;
  EXPECT_NE(r.output.find("interrupted"), std::string::npos) << r.output;
  EXPECT_EQ(network_namespaces(), before);
  EXPECT_EQ(test::run_program("pgrep -f 'skinstreamd.*10\\.213\\.'").exit_code, 1) << "a daemon of the run is still running";
}

TEST(BenchProgram, ShapedLinkWithoutRootSaysWhatItNeeds) {
  if (!is_root() && test::run_program("command -v setpriv").exit_code != 0) GTEST_SKIP() << "needs setpriv to drop root";
  // As root, drop it for the run (util-linux's setpriv), as a user without it would run.
  const std::string as_user = is_root() ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
  if (test::run_program(as_user + "test -x " + std::string(SKINSTREAM_BENCH) + " -a -r " + kDemo + "/live.c3d").exit_code != 0)
    GTEST_SKIP() << "the build is not readable by an unprivileged user here";
  const test::ProgramRun r = test::run_program(as_user + bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo +
                                                                "/live.c3d --seconds 1 --link-mbit 100"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--link-mbit needs root"), std::string::npos) << r.output;
}

// --subjects 2: two actors (the recording twice, apart), each followed by the daemon, with a
// subscriber each, and reported with its own threads' CPU, frames and its subscriber's latency;
// the io and publish threads are nobody's.
TEST(BenchProgram, SeveralSubjectsAreEachReportedWithTheirOwnThreadsAndSubscribers) {
  const test::ProgramRun r = test::run_program(
      bench("--subject " + kDemo + "/subject.sksubj --recording " + kDemo + "/live.c3d --seconds 2 --subjects 2 --subscribers 2 --json"),
      /*stderr_too=*/false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["subjects"], 2);
  const auto& rows = j["per_subject"]["subjects"];
  ASSERT_EQ(rows.size(), 2u);
  double total = 0.0;
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(rows[k]["name"], "Actor" + std::to_string(k + 1));
    EXPECT_GT(rows[k]["frames"]["received"].get<long>(), 0);
    EXPECT_GT(rows[k]["cpu_share_of_one_core"].get<double>(), 0.0);
    EXPECT_EQ(rows[k]["deform"]["threads"], 2);
    EXPECT_GT(rows[k]["subscribers"]["received"].get<long>(), 0);
    EXPECT_LE(rows[k]["subscribers"]["end_to_end"]["count"].get<long>(), rows[k]["subscribers"]["received"].get<long>());
    EXPECT_LE(rows[k]["subscribers"]["end_to_end"]["p50_ms"].get<double>(), rows[k]["subscribers"]["end_to_end"]["p99_ms"].get<double>());
    total += rows[k]["cpu_share_of_one_core"].get<double>();
  }
  EXPECT_DOUBLE_EQ(j["per_subject"]["mean_cpu_share_per_subject"].get<double>(), total / 2);
  EXPECT_EQ(rows[0]["subscribers"]["received"].get<long>() + rows[1]["subscribers"]["received"].get<long>(),
            j["frames"]["received_by_subscribers"].get<long>());
  EXPECT_TRUE(j["per_subject"]["shared_threads_cpu_share"].contains("io")) << j["per_subject"].dump();
  EXPECT_FALSE(j["per_subject"]["shared_threads_cpu_share"].contains("pipeline-0"));
  EXPECT_EQ(j["daemon"]["exit_status"], 0);
}

TEST(BenchProgram, MissingRecordingFailsNamingIt) {
  const std::string absent = test::scratch_path("absent.c3d");
  const test::ProgramRun r = test::run_program(bench("--subject " + kDemo + "/subject.sksubj --recording " + absent + " --seconds 1"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("absent.c3d"), std::string::npos) << r.output;
}

// The daemon refuses it; the bench says so with the daemon's own reason.
TEST(BenchProgram, SubjectThatIsNotOneFailsWithTheDaemonsReason) {
  const std::string corrupt = test::scratch_path("not_a_subject.sksubj");
  { std::ofstream(corrupt) << "not a subject"; }
  const test::ProgramRun r =
      test::run_program(bench("--subject " + corrupt + " --recording " + kDemo + "/live.c3d --seconds 1 --json"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("skinstreamd exited at startup"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not_a_subject.sksubj: not a skinstream subject file"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace skinstream
