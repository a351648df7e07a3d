// The take recorder with its own thread and real files: the control answers, what a take holds
// (read back with the C3D reader), frames outside a take left out, an interrupted take closed at
// the next start, and a folder that cannot be made reported without stopping anything.
#include "server/record/take_recorder.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "protocol/files/c3d.h"
#include "support/test_data.h"
#include "support/wait_until.h"

namespace skinstream::server {
namespace {

const std::vector<std::string> kMarkers{"M1", "M2", "M3"};

std::string fresh_folder(const std::string& name) {
  const std::string path = test::scratch_path(name);
  std::filesystem::remove_all(path);
  return path;
}

TakeRecorderOptions options_for(const std::string& dir) {
  TakeRecorderOptions options;
  options.dir = dir;
  options.unlabelled_slots = 2;
  options.ring_frames = 64;
  options.commit_interval = std::chrono::milliseconds(50);
  options.config = {{"lookahead", 0}};
  return options;
}

void feed(TakeTap& tap, uint32_t first, int count) {
  MarkerFrame frame(static_cast<int>(kMarkers.size()));
  frame.source_rate_hz = 100.0;
  const std::vector<MarkerStatus> status{MarkerStatus::Measured, MarkerStatus::Relabelled,
                                         MarkerStatus::FilledRigid};
  std::vector<Vec3> filled(3);
  for (int i = 0; i < count; ++i) {
    const uint32_t n = first + static_cast<uint32_t>(i);
    frame.frame_number = n;
    frame.labelled = {Vec3(n, 1, 2), missing_point(), Vec3(-1.5, n, 0.25)};
    frame.unlabelled[0] = Vec3(7, 7, n);
    frame.unlabelled_ids[0] = 5;  // one trajectory: one channel
    frame.unlabelled_count = 1;
    tap.record_received(frame);
    filled = {Vec3(n, 1, 2), Vec3(0.5, 0.5, n), Vec3(-1.5, n, 0.25)};
    tap.on_filled({n, 0, 0, filled, status});
    // The writer empties the rings every 50 ms; feed no faster than a capture would.
    if (i % 32 == 31) std::this_thread::sleep_for(std::chrono::milliseconds(60));
  }
}

void wait_idle(const TakeRecorder& recorder) {
  test::wait_until([&] { return recorder.health()["state"] == "idle"; });
}

nlohmann::json sidecar_of(const std::string& dir, const std::string& take) {
  std::ifstream in(std::filesystem::path(dir) / take / "take.json");
  return nlohmann::json::parse(in);
}

TEST(TakeRecorder, ControlAnswersSayWhatWasDoneOrWhyNot) {
  const std::string dir = fresh_folder("takes_answers");
  TakeRecorder recorder(options_for(dir));
  recorder.add_subject("A", "", kMarkers);
  recorder.start_thread();
  EXPECT_EQ(recorder.start("../escape", "test").status, 400);
  EXPECT_EQ(recorder.start(".hidden", "test").status, 400);
  EXPECT_EQ(recorder.stop("test").status, 409);
  const TakeAnswer started = recorder.start("t1", "test");
  EXPECT_EQ(started.status, 201) << started.body;
  EXPECT_EQ(started.body["take"], "t1");
  EXPECT_EQ(recorder.start("t2", "test").status, 409);  // one take at a time
  EXPECT_EQ(recorder.stop("test").status, 200);
  wait_idle(recorder);
  EXPECT_EQ(recorder.start("t1", "test").status, 409);  // its name is taken
  const TakeAnswer named_by_time = recorder.start("", "test");
  EXPECT_EQ(named_by_time.status, 201);
  EXPECT_EQ(named_by_time.body["take"].get<std::string>().rfind("take-", 0), 0u) << named_by_time.body;
}

TEST(TakeRecorder, ATakeHoldsTheFramesOfItsTimeAndNothingElse) {
  const std::string dir = fresh_folder("takes_frames");
  TakeRecorder recorder(options_for(dir));
  TakeTap& tap = recorder.add_subject("Actor 1", "", kMarkers);
  recorder.start_thread();
  feed(tap, 1, 10);  // before the take
  ASSERT_EQ(recorder.start("walk", "operator at 10.0.0.5").status, 201);
  feed(tap, 11, 100);
  ASSERT_EQ(recorder.stop("operator at 10.0.0.5").status, 200);
  feed(tap, 111, 10);  // after it
  wait_idle(recorder);

  const std::filesystem::path take = std::filesystem::path(dir) / "walk";
  const Capture raw = read_c3d((take / "Actor_1.raw.c3d").string());
  ASSERT_EQ(raw.frame_count, 100);
  EXPECT_EQ(raw.rate_hz, 100.0);
  EXPECT_EQ(raw.labels, (std::vector<std::string>{"M1", "M2", "M3", "*1", "*2"}));
  for (int f = 0; f < 100; ++f) {
    const double n = 11 + f;
    EXPECT_EQ(raw.at(f, 0), Vec3(n, 1, 2));
    EXPECT_FALSE(raw.present(f, 1));
    EXPECT_EQ(raw.at(f, 2), Vec3(-1.5, n, 0.25));
    EXPECT_EQ(raw.at(f, 3), Vec3(7, 7, n));
    EXPECT_FALSE(raw.present(f, 4));
  }
  const Capture filled = read_c3d((take / "Actor_1.filled.c3d").string());
  ASSERT_EQ(filled.frame_count, 100);
  EXPECT_EQ(filled.at(99, 1), Vec3(0.5, 0.5, 110));

  std::ifstream table(take / "Actor_1.filled.tsv");
  std::string header, first;
  std::getline(table, header);
  std::getline(table, first);
  EXPECT_EQ(header, "frame\tsource_frame\tsource_time_ns\treceive_time_ns\tstatus");
  EXPECT_EQ(first, "1\t11\t0\t0\tMRG");

  const nlohmann::json sidecar = sidecar_of(dir, "walk");
  EXPECT_EQ(sidecar["state"], "closed");
  EXPECT_EQ(sidecar["started_by"], "operator at 10.0.0.5");
  EXPECT_EQ(sidecar["subjects"][0]["name"], "Actor 1");
  EXPECT_EQ(sidecar["subjects"][0]["raw"]["frames"], 100);
  EXPECT_EQ(sidecar["subjects"][0]["filled"]["frames"], 100);
  EXPECT_EQ(sidecar["subjects"][0]["raw"]["dropped"], 0);
  EXPECT_EQ(sidecar["config"]["lookahead"], 0);
  const nlohmann::json listed = recorder.list();
  ASSERT_EQ(listed["takes"].size(), 1u);
  EXPECT_EQ(listed["takes"][0]["take"], "walk");
  EXPECT_EQ(listed["takes"][0]["subjects"][0]["received_frames"], 100);
}

TEST(TakeRecorder, AnInterruptedTakeIsClosedWhenTheNextRecorderStarts) {
  const std::string dir = fresh_folder("takes_interrupted");
  // A recorder in a child process that ends without closing anything, as kill -9 leaves it.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    TakeRecorder recorder(options_for(dir));
    TakeTap& tap = recorder.add_subject("A", "", kMarkers);
    recorder.start_thread();
    if (recorder.start("cut", "test").status != 201) _exit(2);
    feed(tap, 1, 40);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // several commits
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_EQ(sidecar_of(dir, "cut")["state"], "recording");
  // And a write torn by the kill: half a frame, half a table line.
  const std::string raw = (std::filesystem::path(dir) / "cut" / "A.raw.c3d").string();
  const std::string table = (std::filesystem::path(dir) / "cut" / "A.raw.tsv").string();
  EXPECT_EQ(read_c3d(raw).frame_count, 40);  // readable as it is, before any recovery
  test::write_bytes(raw, test::read_bytes(raw) + std::string(40, '\x11'));
  test::write_bytes(table, test::read_bytes(table) + "41\t41");

  TakeRecorder next(options_for(dir));
  next.add_subject("A", "", kMarkers);
  const std::vector<std::string> said = next.recover_interrupted();
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("take cut (interrupted) closed; A: 40 received, 40 published"), std::string::npos)
      << said[0];
  EXPECT_EQ(sidecar_of(dir, "cut")["state"], "recovered");
  EXPECT_EQ(read_c3d(raw).frame_count, 40);
  EXPECT_EQ(test::read_bytes(table).back(), '\n');
  EXPECT_EQ(next.health()["recovered_at_start"][0], said[0]);
  EXPECT_TRUE(next.recover_interrupted().empty());  // once
}

TEST(TakeRecorder, AFolderThatCannotBeMadeIsReportedAndNothingElseStops) {
  const std::string file = test::scratch_path("takes_not_a_folder");
  test::write_bytes(file, "a file");
  TakeRecorder recorder(options_for(file + "/takes"));
  TakeTap& tap = recorder.add_subject("A", "", kMarkers);
  recorder.start_thread();
  const nlohmann::json health = recorder.health();
  EXPECT_EQ(health["state"], "failed");
  EXPECT_NE(health["error"].get<std::string>().find("Not a directory"), std::string::npos) << health;
  const TakeAnswer answer = recorder.start("t", "test");
  EXPECT_EQ(answer.status, 500);
  EXPECT_NE(answer.body["error"].get<std::string>().find("cannot make"), std::string::npos) << answer.body;
  feed(tap, 1, 5);  // the stream's side goes on, recording nothing
  EXPECT_EQ(tap.received().front(), nullptr);
}

}  // namespace
}  // namespace skinstream::server
