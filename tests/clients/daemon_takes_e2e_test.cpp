// Takes recorded by the real skinstreamd replaying the demo capture: what it received equals the
// capture, what it published equals what a subscriber got, `skinstream fill` of the received take
// and what a daemon replaying the received take publishes; kill -9 at random moments leaves every take
// readable (by our reader and by an independent one written from the C3D specification) up to at most a
// second before the kill, and the next start closes it; a full disk (a small tmpfs) or a folder that cannot
// be made stops the recording, says why, and the stream goes on.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "protocol/files/c3d.h"
#include "server/client/health_probe.h"
#include "server/replay/natnet/natnet_server.h"
#include "server/replay/qtm/qtm_server.h"
#include "support/io_thread.h"
#include "support/loopback_peer.h"
#include "support/program_processes.h"
#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::BackgroundSubscriber;
using test::DaemonProcess;
using test::eventually;

const std::string kDemo = SKINSTREAM_DEMO_DIR;
const std::string kSubject = kDemo + "/subject.sksubj";
const std::string kCapture = kDemo + "/live.c3d";

std::string fresh_folder(const std::string& name) {
  const std::string path = test::scratch_path(name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
  return path;
}

// The one take in `dir`.
std::filesystem::path only_take(const std::string& dir) {
  std::vector<std::filesystem::path> takes;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.is_directory()) takes.push_back(entry.path());
  EXPECT_EQ(takes.size(), 1u) << dir;
  return takes.empty() ? std::filesystem::path(dir) : takes.front();
}

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The per-frame table's lines (without the header), each split at tabs.
std::vector<std::vector<std::string>> table_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::istringstream split(line);
    for (std::string cell; std::getline(split, cell, '\t');) cells.push_back(cell);
    rows.push_back(std::move(cells));
  }
  return rows;
}

nlohmann::json health_of(const DaemonProcess& daemon) {
  try {
    return server::fetch_health(daemon.http_port);
  } catch (const std::exception&) {
    return nlohmann::json::object();
  }
}

std::string recording_state(const DaemonProcess& daemon) {
  const nlohmann::json health = health_of(daemon);
  return health.contains("recording") ? health["recording"].value("state", "") : "";
}

TEST(DaemonDemoTakes, ATakeHoldsWhatWasReceivedAndWhatWasPublished) {
  const Capture capture = read_c3d(kCapture);
  // Half speed, so that the pipeline keeps every frame (the published take is then the fill of
  // the whole received one); a machine too busy for that gets two more attempts.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const std::string dir = fresh_folder("takes_content");
    std::string subscribed;
    {
      DaemonProcess daemon("--subject " + kSubject + " --replay " + kCapture + " --speed 0.5 --record-dir " +
                           dir + " --record-always");
      const test::ProgramRun sub =
          test::run_program(std::string(SKINSTREAM_SUB) + " 127.0.0.1:" + std::to_string(daemon.sub_port) +
                            " --markers --json --frames 120");
      ASSERT_EQ(sub.exit_code, 0) << sub.output;
      subscribed = sub.output;
      ASSERT_TRUE(eventually([&] { return health_of(daemon)["source"].value("state", "") == "finished"; }));
      ASSERT_EQ(daemon.stop(), 0) << daemon.log();
    }
    const std::filesystem::path take = only_take(dir);
    const nlohmann::json sidecar = read_json(take / "take.json");
    EXPECT_EQ(sidecar["state"], "closed");
    EXPECT_EQ(sidecar["started_by"], "record_always");
    EXPECT_EQ(sidecar["subjects"][0]["subject_sha256"].get<std::string>().size(), 64u);

    // Received: every frame of the capture, every sample as it was (floats both ways: exact).
    const Capture raw = read_c3d((take / "subject.raw.c3d").string());
    ASSERT_EQ(raw.frame_count, capture.frame_count);
    int compared = 0;
    for (int p = 0; p < raw.point_count(); ++p) {
      const int source = capture.label_index(raw.labels[p]);
      if (!raw.is_labelled(p)) continue;
      ASSERT_GE(source, 0) << raw.labels[p];
      for (int f = 0; f < raw.frame_count; ++f) {
        ASSERT_EQ(raw.present(f, p), capture.present(f, source)) << raw.labels[p] << " frame " << f;
        if (raw.present(f, p)) {
          ASSERT_EQ(raw.at(f, p), capture.at(f, source)) << raw.labels[p] << " frame " << f;
        }
        ++compared;
      }
    }
    EXPECT_EQ(compared, static_cast<int>(capture.labelled_points().size()) * capture.frame_count);
    // The unlabelled points: every one the capture had in a frame is in one of the take's channels.
    for (int f = 0; f < raw.frame_count; ++f) {
      std::vector<std::array<double, 3>> theirs, ours;
      for (int c : capture.unlabelled_points())
        if (capture.present(f, c))
          theirs.push_back({capture.at(f, c).x(), capture.at(f, c).y(), capture.at(f, c).z()});
      for (int c : raw.unlabelled_points())
        if (raw.present(f, c)) ours.push_back({raw.at(f, c).x(), raw.at(f, c).y(), raw.at(f, c).z()});
      std::sort(theirs.begin(), theirs.end());
      std::sort(ours.begin(), ours.end());
      ASSERT_EQ(ours, theirs) << "unlabelled points of frame " << f;
    }
    const auto raw_rows = table_rows(take / "subject.raw.tsv");
    ASSERT_EQ(raw_rows.size(), static_cast<size_t>(raw.frame_count));
    for (int f = 0; f < raw.frame_count; ++f) EXPECT_EQ(std::stoi(raw_rows[f][1]), capture.first_frame + f);

    // Published: what the subscriber got, frame by frame, sample by sample, status by status.
    const Capture filled = read_c3d((take / "subject.filled.c3d").string());
    const auto filled_rows = table_rows(take / "subject.filled.tsv");
    ASSERT_EQ(filled_rows.size(), static_cast<size_t>(filled.frame_count));
    std::map<int, int> row_of_frame;
    for (size_t r = 0; r < filled_rows.size(); ++r)
      row_of_frame[std::stoi(filled_rows[r][1])] = static_cast<int>(r);
    std::istringstream lines(subscribed);
    int frames_checked = 0;
    for (std::string line; std::getline(lines, line);) {
      const nlohmann::json j = nlohmann::json::parse(line);
      if (!j.contains("frame")) continue;
      ASSERT_TRUE(row_of_frame.count(j["frame"]))
          << "frame " << j["frame"] << " published but not in the take";
      const int row = row_of_frame[j["frame"]];
      const std::vector<float> markers = j["markers"];
      const std::vector<int> status = j["status"];
      ASSERT_EQ(markers.size(), 3u * filled.point_count());
      for (int m = 0; m < filled.point_count(); ++m) {
        for (int a = 0; a < 3; ++a)
          ASSERT_EQ(static_cast<float>(filled.at(row, m)[a]), markers[3 * m + a]) << "frame " << j["frame"];
        EXPECT_EQ(filled_rows[row][4][m], "MRPGH"[status[m]]) << "frame " << j["frame"] << " marker " << m;
      }
      ++frames_checked;
    }
    EXPECT_EQ(frames_checked, 120);

    if (filled.frame_count != raw.frame_count) {
      std::printf("attempt %d: the pipeline published %d of %d frames\n", attempt + 1, filled.frame_count,
                  raw.frame_count);
      continue;
    }
    // The published take is the offline fill of the received one.
    const std::string offline_path = (take / "offline.c3d").string();
    const test::ProgramRun fill =
        test::run_program(std::string(SKINSTREAM_CLI) + " fill --subject " + kSubject + " " +
                          (take / "subject.raw.c3d").string() + " --out " + offline_path);
    ASSERT_EQ(fill.exit_code, 0) << fill.output;
    const Capture offline = read_c3d(offline_path);
    ASSERT_EQ(offline.frame_count, filled.frame_count);
    for (int m = 0; m < filled.point_count(); ++m) {
      const int o = offline.label_index(filled.labels[m]);
      ASSERT_GE(o, 0) << filled.labels[m];
      for (int f = 0; f < filled.frame_count; ++f)
        ASSERT_EQ(offline.at(f, o), filled.at(f, m)) << filled.labels[m] << " frame " << f;
    }

    // The received take replayed into a daemon with the same subject: it publishes what the live
    // session published, frame by frame, bit for bit.
    const std::string again = fresh_folder("takes_replayed");
    {
      DaemonProcess replay("--subject " + kSubject + " --replay " + (take / "subject.raw.c3d").string() +
                           " --speed 0.5 --record-dir " + again + " --record-always");
      ASSERT_TRUE(eventually([&] { return health_of(replay)["source"].value("state", "") == "finished"; }));
      ASSERT_EQ(replay.stop(), 0) << replay.log();
    }
    const std::filesystem::path replayed_take = only_take(again);
    const Capture replayed = read_c3d((replayed_take / "subject.filled.c3d").string());
    if (replayed.frame_count != filled.frame_count) {
      std::printf("attempt %d: the replay's pipeline published %d of %d frames\n", attempt + 1,
                  replayed.frame_count, filled.frame_count);
      continue;
    }
    EXPECT_EQ(test::read_bytes((replayed_take / "subject.filled.c3d").string()),
              test::read_bytes((take / "subject.filled.c3d").string()))
        << "the replay published other markers than the live session";
    const auto replayed_rows = table_rows(replayed_take / "subject.filled.tsv");
    ASSERT_EQ(replayed_rows.size(), filled_rows.size());
    for (size_t r = 0; r < filled_rows.size(); ++r) {
      EXPECT_EQ(replayed_rows[r][1], filled_rows[r][1]) << "frame number, row " << r;
      EXPECT_EQ(replayed_rows[r][4], filled_rows[r][4]) << "statuses, row " << r;
    }
    return;
  }
  FAIL() << "the pipeline dropped frames in all three attempts";
}

// Kill -9 while recording, at random moments: both C3D files of the take read, in our reader and
// in the independent one, with their frames up to at most a second before the kill; the next
// daemon closes the take and says so.
TEST(DaemonDemoTakes, KillNineAtRandomMomentsLeavesTakesReadableToTheLastSecond) {
  const int trials =
      std::getenv("SKINSTREAM_KILL_TRIALS") ? std::atoi(std::getenv("SKINSTREAM_KILL_TRIALS")) : 5;
  std::mt19937 random(std::random_device{}());
  std::uniform_int_distribution<int> run_ms(800, 3000);
  double worst_loss_s = 0.0;
  std::string last_dir;
  for (int trial = 0; trial < trials; ++trial) {
    const std::string dir = fresh_folder("takes_kill_" + std::to_string(trial));
    last_dir = dir;
    DaemonProcess daemon("--subject " + kSubject + " --replay " + kCapture + " --loop --record-dir " + dir +
                         " --record-always");
    ASSERT_TRUE(eventually([&] { return recording_state(daemon) == "recording"; }));
    std::this_thread::sleep_for(std::chrono::milliseconds(run_ms(random)));
    const int64_t killed_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::system_clock::now().time_since_epoch())
                                  .count();
    ASSERT_EQ(kill(daemon.pid(), SIGKILL), 0);
    daemon.stop();

    const std::filesystem::path take = only_take(dir);
    EXPECT_EQ(read_json(take / "take.json")["state"], "recording");
    for (const char* kind : {"raw", "filled"}) {
      const std::string c3d = (take / (std::string("subject.") + kind + ".c3d")).string();
      const Capture ours = read_c3d(c3d);
      const test::ProgramRun theirs = test::run_program(
          "python3 " + std::string(SKINSTREAM_SOURCE_DIR) + "/tests/support/c3d_spec_reader.py " + c3d,
          false);
      ASSERT_EQ(theirs.exit_code, 0) << theirs.output;
      const nlohmann::json independent = nlohmann::json::parse(theirs.output);
      EXPECT_EQ(independent["frames"], ours.frame_count) << c3d;
      EXPECT_EQ(independent["points"], ours.point_count()) << c3d;
      if (ours.frame_count > 0 && ours.present(ours.frame_count - 1, 0)) {
        EXPECT_FLOAT_EQ(independent["last"][0][0].get<float>(),
                        static_cast<float>(ours.at(ours.frame_count - 1, 0).x()));
      }
      const auto rows = table_rows(take / (std::string("subject.") + kind + ".tsv"));
      ASSERT_GE(rows.size(), static_cast<size_t>(ours.frame_count))
          << "the table is synced before its C3D file";
      ASSERT_GT(ours.frame_count, 0) << c3d << " after " << trial;
      const int64_t last_received_ns = std::stoll(rows[ours.frame_count - 1][3]);
      const double lost_s = static_cast<double>(killed_ns - last_received_ns) * 1e-9;
      worst_loss_s = std::max(worst_loss_s, lost_s);
      EXPECT_LE(lost_s, 1.0) << c3d << ": its last readable frame came " << lost_s << " s before the kill";
    }
  }
  std::printf("%d kills: the readable takes ended at most %.3f s before the kill\n", trials, worst_loss_s);

  // The next daemon closes the last one, counting in what the kill left unsynced.
  const std::filesystem::path take = only_take(last_dir);
  const int before = read_c3d((take / "subject.raw.c3d").string()).frame_count;
  DaemonProcess next("--subject " + kSubject + " --replay " + kCapture + " --record-dir " + last_dir);
  const nlohmann::json recovered = health_of(next)["recording"]["recovered_at_start"];
  ASSERT_EQ(recovered.size(), 1u) << health_of(next);
  EXPECT_NE(recovered[0].get<std::string>().find("(interrupted) closed"), std::string::npos) << recovered;
  EXPECT_EQ(next.stop(), 0);
  EXPECT_NE(next.log().find("(interrupted) closed"), std::string::npos) << next.log();
  const nlohmann::json sidecar = read_json(take / "take.json");
  EXPECT_EQ(sidecar["state"], "recovered");
  EXPECT_GE(read_c3d((take / "subject.raw.c3d").string()).frame_count, before);
  EXPECT_EQ(sidecar["subjects"][0]["raw"]["frames"],
            read_c3d((take / "subject.raw.c3d").string()).frame_count);
}

TEST(DaemonDemoTakes, AFullDiskStopsTheTakeAndTheStreamGoesOn) {
  const std::string dir = fresh_folder("takes_full_disk");
  // A filesystem of 2 MB of our own: about a second and a half of the demo's take.
  if (mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=2m") != 0)
    GTEST_SKIP() << "cannot mount a small tmpfs (needs root): " << std::strerror(errno);
  struct Unmount {
    std::string dir;
    ~Unmount() { umount2(dir.c_str(), MNT_DETACH); }
  } unmount{dir};

  DaemonProcess daemon("--subject " + kSubject + " --replay " + kCapture + " --loop --record-dir " + dir +
                       " --record-always");
  BackgroundSubscriber subscriber(daemon.sub_port, 0);
  ASSERT_TRUE(eventually([&] { return recording_state(daemon) == "failed"; }, std::chrono::seconds(30)))
      << health_of(daemon);
  const nlohmann::json recording = health_of(daemon)["recording"];
  EXPECT_NE(recording["error"].get<std::string>().find("No space left on device"), std::string::npos)
      << recording;
  const long frames_then = subscriber.frames();
  ASSERT_TRUE(eventually([&] { return subscriber.frames() >= frames_then + 120; }))
      << "the stream stopped with the recording";
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  EXPECT_NE(daemon.log().find(
                "No space left on device (its files read up to the last second written; the stream goes on)"),
            std::string::npos)
      << daemon.log();

  // The files read as they are, up to their last commit; take.json may still say "recording"
  // (the full disk refused its update too).
  const std::filesystem::path take = only_take(dir);
  const int written = read_c3d((take / "subject.raw.c3d").string()).frame_count;
  EXPECT_GT(written, 0);
  read_c3d((take / "subject.filled.c3d").string());  // readable (throws otherwise)

  // Space made, the next daemon closes the take.
  ASSERT_EQ(mount("tmpfs", dir.c_str(), "tmpfs", MS_REMOUNT, "size=16m"), 0) << std::strerror(errno);
  DaemonProcess next("--subject " + kSubject + " --replay " + kCapture + " --record-dir " + dir);
  const nlohmann::json recovered = health_of(next)["recording"]["recovered_at_start"];
  ASSERT_EQ(recovered.size(), 1u) << health_of(next);
  EXPECT_EQ(next.stop(), 0);
  EXPECT_EQ(read_json(take / "take.json")["state"], "recovered");
  EXPECT_GE(read_c3d((take / "subject.raw.c3d").string()).frame_count, written);
}

TEST(DaemonDemoTakes, ATakesFolderThatCannotBeMadeIsReportedAndTheStreamGoesOn) {
  const std::string file = test::scratch_path("takes_in_a_file_" + std::to_string(getpid()));
  test::write_bytes(file, "not a folder");
  DaemonProcess daemon("--subject " + kSubject + " --replay " + kCapture + " --loop --record-dir " + file +
                       "/takes --record-always");
  ASSERT_GT(daemon.http_port, 0) << daemon.log();
  BackgroundSubscriber subscriber(daemon.sub_port, 0);
  const nlohmann::json recording = health_of(daemon)["recording"];
  EXPECT_EQ(recording["state"], "failed");
  EXPECT_NE(recording["error"].get<std::string>().find("Not a directory"), std::string::npos) << recording;
  ASSERT_TRUE(eventually([&] { return subscriber.frames() >= 60; }));
  EXPECT_EQ(daemon.stop(), 0);
}

// With record_with_source, a take while the capture system records one: NatNet's frame flag
// (Motive) and QTM RT's capture events, from the replay servers flagging frames [60, 180) of 240.
void expect_take_follows_capture_system(bool natnet) {
  const Capture capture = read_c3d(kCapture);
  test::IoThread server_io;
  std::unique_ptr<server::QtmServer> qtm;
  std::unique_ptr<server::NatNetServer> natnet_server;
  std::string source;
  if (natnet) {
    server::NatNetServerOptions options;
    options.bind_address = "127.0.0.1";
    options.command_port = 0;
    options.multicast = false;
    options.recording_first = 60;
    options.recording_end = 180;
    natnet_server = std::make_unique<server::NatNetServer>(
        server_io.io, std::vector<ReplaySubject>{{"demo", &capture}}, options);
    source = "--natnet 127.0.0.1:" + std::to_string(server_io.call([&] {
               natnet_server->start();
               return natnet_server->command_port();
             }));
  } else {
    server::QtmServerOptions options;
    options.bind_address = "127.0.0.1";
    options.port = 0;
    options.capture_first = 60;
    options.capture_end = 180;
    qtm = std::make_unique<server::QtmServer>(server_io.io, std::vector<ReplaySubject>{{"demo", &capture}},
                                              options);
    source = "--qtm 127.0.0.1:" + std::to_string(server_io.call([&] {
               qtm->start();
               return qtm->port();
             }));
  }
  const std::string dir = fresh_folder(natnet ? "takes_natnet" : "takes_qtm");
  DaemonProcess daemon("--subject " + kSubject + " " + source + " --record-dir " + dir +
                       " --record-with-source");
  const bool closed =
      eventually([&] { return health_of(daemon)["recording"].value("takes_closed", 0) == 1; });
  const nlohmann::json health = health_of(daemon);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  server_io.call([&] {
    if (qtm) qtm->stop();
    if (natnet_server) natnet_server->stop();
  });
  ASSERT_TRUE(closed) << health["recording"];

  const std::filesystem::path take = only_take(dir);
  const nlohmann::json sidecar = read_json(take / "take.json");
  EXPECT_EQ(sidecar["state"], "closed");
  EXPECT_EQ(sidecar["started_by"], "the capture system");
  // The frames the capture system recorded, give or take the frame or two an event and the
  // frames cross on their way (QTM's events and frames are queued apart).
  const auto rows = table_rows(take / "subject.raw.tsv");
  ASSERT_FALSE(rows.empty());
  const int first = std::stoi(rows.front()[1]) - capture.first_frame,
            last = std::stoi(rows.back()[1]) - capture.first_frame;
  EXPECT_NEAR(first, 60, 2) << "first frame of the take";
  EXPECT_NEAR(last, 179, 2) << "last frame of the take";
  EXPECT_GE(rows.size(), 116u);
}

TEST(DaemonDemoTakes, ATakeFollowsMotivesRecordingOverNatNet) { expect_take_follows_capture_system(true); }
TEST(DaemonDemoTakes, ATakeFollowsQtmsCaptureEvents) { expect_take_follows_capture_system(false); }

// The operator's control API on the real daemon: skinstream-ctl with the token starts, stops and
// lists a take; without it, or with a wrong one, nothing happens, it is counted, and the token
// never reaches the log.
TEST(DaemonDemoTakes, TheOperatorRecordsATakeWithSkinstreamCtlAndNobodyElseCan) {
  const std::string dir = fresh_folder("takes_ctl");
  const std::string token = "stage-control-token-4711";
  const std::string token_file = test::scratch_path("control_token_" + std::to_string(getpid()));
  test::write_bytes(token_file, token + "\n");
  ASSERT_EQ(chmod(token_file.c_str(), 0600), 0);
  DaemonProcess daemon("--subject " + kSubject + " --replay " + kCapture + " --loop --record-dir " + dir +
                       " --control-token-file " + token_file);
  const std::string ctl = std::string(SKINSTREAM_CTL) + " --port " + std::to_string(daemon.http_port);
  const auto ctl_run = [&](const std::string& arguments) {
    return test::run_program("SKINSTREAM_CONTROL_TOKEN= " + ctl + " " + arguments, false);
  };

  // Nobody else: no token, a wrong one, raw requests without one.
  const std::string wrong_file = token_file + ".wrong";
  test::write_bytes(wrong_file, "not-the-stage-token-0000\n");
  ASSERT_EQ(chmod(wrong_file.c_str(), 0600), 0);
  EXPECT_EQ(ctl_run("--token-file " + wrong_file + " take start stolen").exit_code, 1);
  const std::string unauthorised = test::http_exchange_within(
      daemon.http_port, "POST /takes HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
      std::chrono::seconds(10));
  EXPECT_NE(unauthorised.find("401"), std::string::npos) << unauthorised;
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "a refused request started a take";
  const nlohmann::json refused = health_of(daemon)["control"];
  EXPECT_EQ(refused["refused_403"], 1) << refused;
  EXPECT_EQ(refused["refused_401"], 1) << refused;

  // The operator.
  const test::ProgramRun started = ctl_run("--token-file " + token_file + " --operator anna take start walk");
  ASSERT_EQ(started.exit_code, 0) << started.output;
  EXPECT_EQ(nlohmann::json::parse(started.output)["take"], "walk");
  ASSERT_TRUE(eventually([&] {
    const nlohmann::json subjects = health_of(daemon)["recording"]["subjects"];
    return subjects.contains("subject") && subjects["subject"].value("received_frames", 0) >= 60;
  }));
  const test::ProgramRun again = ctl_run("--token-file " + token_file + " take start other");
  EXPECT_EQ(again.exit_code, 1) << again.output;  // one take at a time: 409, said in one line
  ASSERT_EQ(ctl_run("--token-file " + token_file + " take stop").exit_code, 0);
  ASSERT_TRUE(eventually([&] { return health_of(daemon)["recording"].value("state", "") == "idle"; }));
  const test::ProgramRun listed = ctl_run("--token-file " + token_file + " takes");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  const nlohmann::json takes = nlohmann::json::parse(listed.output)["takes"];
  ASSERT_EQ(takes.size(), 1u) << listed.output;
  EXPECT_EQ(takes[0]["take"], "walk");
  EXPECT_EQ(takes[0]["state"], "closed");
  EXPECT_EQ(takes[0]["started_by"], "control from 127.0.0.1 (anna)");
  EXPECT_GE(takes[0]["subjects"][0]["received_frames"].get<int>(), 60);
  EXPECT_EQ(daemon.stop(), 0);
  EXPECT_EQ(daemon.log().find(token), std::string::npos) << "the token reached the log";
  EXPECT_NE(daemon.log().find("take walk started by control from 127.0.0.1 (anna)"), std::string::npos)
      << daemon.log();
}

TEST(DaemonDemoTakes, RecordAlwaysWithoutAFolderIsRefusedAtStart) {
  const test::ProgramRun run = test::run_program(std::string(SKINSTREAMD) + " --subject " + kSubject +
                                                 " --record-always --http-port 0 --sub-port 0");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("record_always needs record_dir"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace skinstream
