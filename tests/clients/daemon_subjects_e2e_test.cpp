// Several actors on one stage, with the real programs on loopback: skinstream-replay streams two
// recordings of one marker template as the Vicon subjects Actor1 and Actor2, and skinstreamd
// follows them by name. A stage grows past one machine by running one daemon per group of
// subjects, each a separate client of the same Vicon stream.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <thread>

#include "protocol/files/capture_file.h"
#include "protocol/subscriber/subscriber_stream.h"
#include "server/beast.h"
#include "server/client/health_probe.h"
#include "support/program_processes.h"
#include "support/program_run.h"
#include "support/recording_match.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::DaemonProcess;
using test::ProgramRun;
using test::ReplayProcess;

constexpr double kApartMm = 4000.0;  // Actor2 stands this far from Actor1 along x

class DaemonSubjects : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // Per process: ctest runs each test as its own process, several at once.
    const std::string own = std::to_string(getpid());
    subject_ = test::scratch_path("subjects_subject_" + own + ".sks");
    const ProgramRun built = test::run_program(std::string(SKINSTREAM_CLI) + " build-subject --capture " +
                                               test::source_path("replay_data/cmu/85_02.c3d") + " --out " + subject_);
    ASSERT_EQ(built.exit_code, 0) << built.output;
    // Two takes of the same performer's template: 85_12 where it was, 85_02 moved 4 m away.
    std::vector<int> channels;
    for (int c = 0; c < 41; ++c) channels.push_back(c);
    const Capture first = read_capture(test::source_path("replay_data/cmu/85_12.c3d")).select(channels, 0, kTakeFrames);
    Capture second = read_capture(test::source_path("replay_data/cmu/85_02.c3d")).select(channels, 0, kTakeFrames);
    second.first_frame = first.first_frame;  // one stream, one numbering
    for (int f = 0; f < second.frame_count; ++f)
      for (int c = 0; c < second.point_count(); ++c)
        if (second.present(f, c)) second.at(f, c) += Vec3(kApartMm, 0.0, 0.0);
    take_a_ = test::scratch_path("subjects_a_" + own + ".c3d");
    take_b_ = test::scratch_path("subjects_b_" + own + ".c3d");
    write_capture(first, take_a_);
    write_capture(second, take_b_);
  }
  static void TearDownTestSuite() {
    for (const std::string& path : {subject_, take_a_, take_b_}) std::remove(path.c_str());
  }
  static std::string replay_arguments() { return take_a_ + " " + take_b_; }

  static constexpr int kTakeFrames = 240;
  static inline std::string subject_, take_a_, take_b_;
};

// Two daemons, each following one actor, read one replay server at once: each gets its own
// actor's frames, and the server serves both.
TEST_F(DaemonSubjects, TwoDaemonsReadOneReplayServerEachFollowingItsOwnActor) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  const std::string vicon = " --vicon 127.0.0.1:" + std::to_string(replay.port);
  DaemonProcess first("--subject Actor1=" + subject_ + vicon);
  DaemonProcess second("--subject Actor2=" + subject_ + vicon);
  constexpr int kFrames = 120;
  auto subscribe = [&](const DaemonProcess& daemon) {
    return test::run_program(std::string(SKINSTREAM_SUB) + " 127.0.0.1:" + std::to_string(daemon.sub_port) +
                             " --markers --json --frames " + std::to_string(kFrames));
  };
  ProgramRun from_second;
  std::thread other([&] { from_second = subscribe(second); });
  const ProgramRun from_first = subscribe(first);
  other.join();
  const nlohmann::json health_first = server::fetch_health(first.http_port), health_second = server::fetch_health(second.http_port);
  EXPECT_EQ(first.stop(), 0) << first.log();
  EXPECT_EQ(second.stop(), 0) << second.log();
  ASSERT_EQ(from_first.exit_code, 0) << from_first.output << first.log();
  ASSERT_EQ(from_second.exit_code, 0) << from_second.output << second.log();
  EXPECT_EQ(health_first["subject"]["detail"], "follows \"Actor1\": 41 of the subject's 41 markers labelled");
  EXPECT_EQ(health_second["subject"]["detail"], "follows \"Actor2\": 41 of the subject's 41 markers labelled");

  const std::vector<nlohmann::json> actor1 = test::frames_of(from_first.output), actor2 = test::frames_of(from_second.output);
  ASSERT_EQ(actor1.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(actor2.size(), static_cast<size_t>(kFrames));
  // Each its own actor's measured samples, and no marker (measured or filled) nearer the other.
  test::expect_frames_follow_recording(read_capture(take_a_), actor1, kApartMm);
  test::expect_frames_follow_recording(read_capture(take_b_), actor2, -kApartMm);
}

// One daemon follows both actors; skinstream-sub names the one it wants (protocol version 2), and
// a name the daemon does not serve is refused with the reason.
TEST_F(DaemonSubjects, OneDaemonServesBothActorsToSubscribersNamingThem) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  DaemonProcess daemon("--subject Actor1=" + subject_ + " --subject Actor2=" + subject_ + " --vicon 127.0.0.1:" +
                       std::to_string(replay.port));
  const std::string sub = std::string(SKINSTREAM_SUB) + " 127.0.0.1:" + std::to_string(daemon.sub_port);
  constexpr int kFrames = 120;
  ProgramRun actor2;
  std::thread other([&] { actor2 = test::run_program(sub + " --subject Actor2 --markers --json --frames " + std::to_string(kFrames)); });
  const ProgramRun actor1 = test::run_program(sub + " --subject Actor1 --markers --json --frames " + std::to_string(kFrames));
  other.join();
  const ProgramRun nobody = test::run_program(sub + " --subject Nobody --frames 1");
  const nlohmann::json health = server::fetch_health(daemon.http_port);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  ASSERT_EQ(actor1.exit_code, 0) << actor1.output << daemon.log();
  ASSERT_EQ(actor2.exit_code, 0) << actor2.output << daemon.log();
  test::expect_frames_follow_recording(read_capture(take_a_), test::frames_of(actor1.output), kApartMm);
  test::expect_frames_follow_recording(read_capture(take_b_), test::frames_of(actor2.output), -kApartMm);
  EXPECT_EQ(nobody.exit_code, 1);
  EXPECT_NE(nobody.output.find("the daemon refused this subscriber: no subject \"Nobody\" here (this daemon serves \"Actor1\", \"Actor2\")"),
            std::string::npos)
      << nobody.output;
  ASSERT_EQ(health["subjects"].size(), 2u);
  for (const auto& subject : health["subjects"]) EXPECT_TRUE(subject["present"].get<bool>()) << subject.dump();
}

// The summary line of skinstream-sub --json output.
nlohmann::json summary_of(const std::string& sub_output) {
  std::istringstream lines(sub_output);
  nlohmann::json summary;
  for (std::string line; std::getline(lines, line);)
    if (const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
        j.is_object() && j.contains("summary"))
      summary = j["summary"];
  return summary;
}

// Frame numbers that do not follow the one before (a frame missed), in a subscriber's frames.
int frames_missed(const std::vector<nlohmann::json>& frames) {
  int missed = 0;
  for (size_t i = 1; i < frames.size(); ++i)
    if (frames[i]["frame"].get<int64_t>() != frames[i - 1]["frame"].get<int64_t>() + 1) ++missed;
  return missed;
}

// A stage with two actors and the control API on: skinstream-replay streams both, the daemon
// serves each with a subject fitted to the body template, and the operator's skinstream-ctl
// changes Actor2 while both have a subscriber.
class DaemonSubjectChanges : public DaemonSubjects {
 protected:
  static void SetUpTestSuite() {
    DaemonSubjects::SetUpTestSuite();
    const std::string own = std::to_string(getpid());
    meshed_ = test::scratch_path("changes_meshed_" + own + ".sks");
    const ProgramRun built = test::run_program(std::string(SKINSTREAM_CLI) + " build-subject --capture " +
                                               test::source_path("replay_data/cmu/85_02.c3d") + " --mesh " +
                                               mesh() + " --out " + meshed_);
    ASSERT_EQ(built.exit_code, 0) << built.output;
  }
  static std::string mesh() {
    return test::source_path("replay_data/makehuman/makehuman_hm08_body_only.obj");
  }

  void SetUp() override {
    const std::string own = std::to_string(getpid());
    token_file_ = test::scratch_path("changes_token_" + own);
    test::write_bytes(token_file_, "changes-token-0123456789\n");
    ASSERT_EQ(chmod(token_file_.c_str(), 0600), 0);
    calibrations_ = test::scratch_path("changes_calibrations_" + own);
    config_ = test::scratch_path("changes_config_" + own + ".json");
    test::write_bytes(config_,
                      nlohmann::json{{"calibration_dir", calibrations_}, {"deform_threads", 1}}.dump());
  }
  std::string daemon_arguments(int replay_port, bool both = true) const {
    return "--config " + config_ + " --subject Actor1=" + meshed_ +
           (both ? " --subject Actor2=" + meshed_ : "") +
           " --vicon 127.0.0.1:" + std::to_string(replay_port) + " --control-token-file " + token_file_;
  }
  std::string ctl(const DaemonProcess& daemon) const {
    return "SKINSTREAM_CONTROL_TOKEN= " + std::string(SKINSTREAM_CTL) + " --port " +
           std::to_string(daemon.http_port) + " --token-file " + token_file_ + " --operator anna ";
  }
  static std::string sub(const DaemonProcess& daemon) {
    return std::string(SKINSTREAM_SUB) + " 127.0.0.1:" + std::to_string(daemon.sub_port) + " --json ";
  }

  static inline std::string meshed_;
  std::string token_file_, calibrations_, config_;
};

// Actor2 calibrated live: 3 s of its range of motion recorded from the stream, built by
// build-subject in its own process, checked and swapped in between two frames. Its parameter
// subscriber is sent the new MeshInfo and Model and carries on; Actor1's subscriber misses no
// frame.
TEST_F(DaemonSubjectChanges, AnActorCalibratedLiveIsSwappedInWhileTheOtherMissesNoFrame) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  DaemonProcess daemon(daemon_arguments(replay.port));
  // Both subscribers run until the daemon stops.
  ProgramRun actor1, actor2;
  std::thread watcher([&] { actor1 = test::run_program(sub(daemon) + "--subject Actor1 --no-mesh", false); });
  std::thread changed(
      [&] { actor2 = test::run_program(sub(daemon) + "--subject Actor2 --encoding parameters", false); });
  std::this_thread::sleep_for(std::chrono::seconds(2));
  // 3 s here; SKINSTREAM_CALIBRATION_SECONDS=30 measures the stage's 30 s (docs/measurements-log.md).
  const char* asked = std::getenv("SKINSTREAM_CALIBRATION_SECONDS");
  const int seconds = asked ? std::atoi(asked) : 3;
  const ProgramRun calibrated = test::run_program(
      ctl(daemon) + "subject calibrate Actor2 --seconds " + std::to_string(seconds) + " --mesh " + mesh(),
      false);
  const int64_t swapped_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const nlohmann::json health = server::fetch_health(daemon.http_port);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  watcher.join();
  changed.join();

  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.output << daemon.log();
  const nlohmann::json change = nlohmann::json::parse(calibrated.output);
  EXPECT_EQ(change["state"], "done");
  EXPECT_EQ(change["kind"], "calibration");
  EXPECT_EQ(change["frames_recorded"], 120 * seconds);
  EXPECT_EQ(change["markers"], 41);
  EXPECT_NE(change["who"].get<std::string>().find("anna"), std::string::npos);
  const std::string built = change["subject_file"];
  EXPECT_TRUE(std::filesystem::exists(built)) << built;
  EXPECT_TRUE(std::filesystem::exists(change["capture"].get<std::string>()));
  std::printf("calibration of %d s: build %.2f s, load %.2f s, swap %.1f ms, in all %.2f s\n", seconds,
              change["build_seconds"].get<double>(), change["load_seconds"].get<double>(),
              change["swap_ms"].get<double>(), change["seconds_in_all"].get<double>());

  ASSERT_EQ(actor2.exit_code, 0) << actor2.output.substr(0, 2000) << daemon.log();
  const nlohmann::json summary2 = summary_of(actor2.output);
  EXPECT_EQ(summary2["meshes_received"], 2)
      << summary2.dump();  // the first subject's, then the calibrated one's
  EXPECT_EQ(summary2["frames_rejected"], 0) << summary2.dump();
  int after_swap = 0;  // frames of the calibrated subject, taken by the same subscriber
  for (const nlohmann::json& frame : test::frames_of(actor2.output))
    after_swap += frame["arrival_time_ns"].get<int64_t>() > swapped_ns;
  EXPECT_GE(after_swap, 120);

  ASSERT_EQ(actor1.exit_code, 0) << actor1.output.substr(0, 2000) << daemon.log();
  const std::vector<nlohmann::json> frames1 = test::frames_of(actor1.output);
  EXPECT_GE(frames1.size(), 120u * 10);  // 2 s, 3 s recorded, the build, 2 s
  EXPECT_EQ(frames_missed(frames1), 0);
  EXPECT_EQ(summary_of(actor1.output)["pipeline_dropped"], 0);
  EXPECT_EQ(summary_of(actor1.output)["subscriber_dropped"], 0);

  ASSERT_EQ(health["subjects"].size(), 2u);
  EXPECT_EQ(health["subjects"][0]["file"], meshed_);
  EXPECT_EQ(health["subjects"][0]["frames"]["dropped"], 0);
  EXPECT_EQ(health["subjects"][1]["file"], built);
  EXPECT_EQ(health["subjects"][1]["change"]["state"], "done");
  EXPECT_EQ(health["subjects"][1]["model_epoch"], 1);
}

// What fails leaves the subject served as it was and says why: a calibration fitting a mesh that
// is not a body (build-subject refuses it), a subject file without a mesh for a subject served
// with one, a file that is not a subject file; the control API refuses unknown subjects and bad
// requests at once. The subscriber never gets another MeshInfo.
TEST_F(DaemonSubjectChanges, AChangeThatFailsLeavesTheServedSubjectAndSaysWhy) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  DaemonProcess daemon(daemon_arguments(replay.port));
  ProgramRun actor2;
  std::thread watcher(
      [&] { actor2 = test::run_program(sub(daemon) + "--subject Actor2 --encoding parameters", false); });
  const std::string cube = test::scratch_path("changes_cube.obj");
  test::write_bytes(cube, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
  const ProgramRun not_a_body =
      test::run_program(ctl(daemon) + "subject calibrate Actor2 --seconds 1 --mesh " + cube);
  const ProgramRun markers_only = test::run_program(ctl(daemon) + "subject load Actor2 " + subject_);
  const std::string garbage = test::scratch_path("changes_garbage.sks");
  test::write_bytes(garbage, "not a subject file");
  const ProgramRun not_a_subject = test::run_program(ctl(daemon) + "subject load Actor2 " + garbage);
  const ProgramRun nobody = test::run_program(ctl(daemon) + "subject load Nobody " + meshed_);
  const ProgramRun no_mesh =
      test::run_program(ctl(daemon) + "subject calibrate Actor2 --seconds 1 --mesh /no/such/body.obj");
  const ProgramRun no_token = test::run_program(
      "SKINSTREAM_CONTROL_TOKEN= " + std::string(SKINSTREAM_CTL) + " --port " +
      std::to_string(daemon.http_port) + " --token-file " + garbage + " subject load Actor2 " + meshed_);
  const nlohmann::json health = server::fetch_health(daemon.http_port);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  watcher.join();

  EXPECT_EQ(not_a_body.exit_code, 1) << not_a_body.output;
  EXPECT_NE(not_a_body.output.find("calibration failed: build-subject exited with"), std::string::npos)
      << not_a_body.output;
  EXPECT_EQ(markers_only.exit_code, 1) << markers_only.output;
  EXPECT_NE(markers_only.output.find("has no deformation model"), std::string::npos) << markers_only.output;
  EXPECT_EQ(not_a_subject.exit_code, 1) << not_a_subject.output;
  EXPECT_NE(not_a_subject.output.find(garbage), std::string::npos) << not_a_subject.output;
  EXPECT_EQ(nobody.exit_code, 1);
  EXPECT_NE(nobody.output.find("404 no subject 'Nobody' here"), std::string::npos) << nobody.output;
  EXPECT_EQ(no_mesh.exit_code, 1);
  EXPECT_NE(no_mesh.output.find("no such file"), std::string::npos) << no_mesh.output;
  EXPECT_EQ(no_token.exit_code, 1);
  EXPECT_NE(no_token.output.find("403"), std::string::npos) << no_token.output;

  ASSERT_EQ(actor2.exit_code, 0) << actor2.output.substr(0, 2000) << daemon.log();
  EXPECT_EQ(summary_of(actor2.output)["meshes_received"], 1);
  EXPECT_EQ(summary_of(actor2.output)["frames_rejected"], 0);
  EXPECT_EQ(health["subjects"][1]["file"], meshed_);
  EXPECT_EQ(health["subjects"][1]["model_epoch"], 0);
  EXPECT_EQ(health["subjects"][1]["change"]["state"], "failed");
  EXPECT_EQ(health["control"]["refused_403"], 1);
}

// Actor2 steps onto the stage: added at run time from a subject file, its subscriber gets its
// frames (its own actor's, not Actor1's); then removed: its subscriber is told why and closed.
// Actor1's subscriber misses no frame meanwhile; the last subject cannot be removed.
TEST_F(DaemonSubjectChanges, ASubjectAddedAndRemovedAtRunTimeWhileTheOtherMissesNoFrame) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  DaemonProcess daemon(daemon_arguments(replay.port, /*both=*/false));
  ProgramRun actor1, leaving;
  std::thread watcher([&] { actor1 = test::run_program(sub(daemon) + "--subject Actor1 --no-mesh", false); });
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const ProgramRun garbage = test::run_program(ctl(daemon) + "subject add Actor2 " + take_a_);
  const ProgramRun added = test::run_program(ctl(daemon) + "subject add Actor2 " + meshed_, false);
  const ProgramRun again = test::run_program(ctl(daemon) + "subject add Actor2 " + meshed_);
  const ProgramRun actor2 = test::run_program(sub(daemon) + "--subject Actor2 --markers --frames 120", false);
  std::thread stays([&] { leaving = test::run_program(sub(daemon) + "--subject Actor2 --no-mesh"); });
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const ProgramRun removed = test::run_program(ctl(daemon) + "subject remove Actor2", false);
  stays.join();
  const ProgramRun last = test::run_program(ctl(daemon) + "subject remove Actor1");
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const nlohmann::json health = server::fetch_health(daemon.http_port);
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  watcher.join();

  EXPECT_EQ(garbage.exit_code, 1) << garbage.output;
  EXPECT_NE(garbage.output.find("add failed: " + take_a_), std::string::npos) << garbage.output;
  ASSERT_EQ(added.exit_code, 0) << added.output << daemon.log();
  EXPECT_EQ(nlohmann::json::parse(added.output)["state"], "done");
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.output.find("409 subject 'Actor2' is served already"), std::string::npos) << again.output;
  ASSERT_EQ(actor2.exit_code, 0) << actor2.output.substr(0, 2000) << daemon.log();
  test::expect_frames_follow_recording(read_capture(take_b_), test::frames_of(actor2.output), -kApartMm);
  ASSERT_EQ(removed.exit_code, 0) << removed.output << daemon.log();
  EXPECT_EQ(nlohmann::json::parse(removed.output)["removed"], "Actor2");
  EXPECT_EQ(leaving.exit_code, 1) << leaving.output;
  EXPECT_NE(
      leaving.output.find("the daemon refused this subscriber: subject Actor2 was removed from this daemon"),
      std::string::npos)
      << leaving.output;
  EXPECT_EQ(last.exit_code, 1);
  EXPECT_NE(last.output.find("409 subject Actor1 is the only one served"), std::string::npos) << last.output;

  ASSERT_EQ(actor1.exit_code, 0) << actor1.output.substr(0, 2000) << daemon.log();
  const std::vector<nlohmann::json> frames1 = test::frames_of(actor1.output);
  EXPECT_GE(frames1.size(), 120u * 4);
  EXPECT_EQ(frames_missed(frames1), 0);
  EXPECT_EQ(summary_of(actor1.output)["pipeline_dropped"], 0);
  ASSERT_EQ(health["subjects"].size(), 1u);
  EXPECT_EQ(health["subjects"][0]["name"], "Actor1");
  EXPECT_EQ(health["subjects"][0]["frames"]["dropped"], 0);
}

// The first subject removed: a subscriber that names none now gets the next one (the subscriber
// port and the WebSocket path both start a subscriber in the first subject's hub, asked anew at
// each connection), and the removed one's subscriber is told.
TEST_F(DaemonSubjectChanges, WhenTheFirstSubjectIsRemovedTheNextOneIsTheDefault) {
  ReplayProcess replay(replay_arguments(), 0, "--subject Actor1 --subject Actor2");
  DaemonProcess daemon(daemon_arguments(replay.port));
  ProgramRun leaving;
  std::thread stays([&] { leaving = test::run_program(sub(daemon) + "--no-mesh"); });
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const ProgramRun removed = test::run_program(ctl(daemon) + "subject remove Actor1", false);
  stays.join();
  const ProgramRun unnamed = test::run_program(sub(daemon) + "--markers --frames 60", false);
  // Over WebSocket, a Hello naming no subject: Actor2's MeshInfo.
  std::string websocket_subject;
  {
    namespace beast = server::beast;
    namespace websocket = server::websocket;
    server::asio::io_context io;
    websocket::stream<beast::tcp_stream> ws(io);
    beast::get_lowest_layer(ws).connect(server::tcp::endpoint(server::asio::ip::make_address("127.0.0.1"),
                                                              static_cast<unsigned short>(daemon.http_port)));
    ws.handshake("127.0.0.1", "/stream");
    ws.binary(true);
    subscriber::Hello hello;
    hello.version = subscriber::kVersion2;
    hello.wants = subscriber::kWantMarkers | subscriber::kWantNoMesh;
    ws.write(server::asio::buffer(subscriber::encode_hello(hello)));
    for (int message = 0; message < 10 && websocket_subject.empty(); ++message) {
      beast::flat_buffer buffer;
      ws.read(buffer);
      const std::span<const unsigned char> bytes(static_cast<const unsigned char*>(buffer.cdata().data()),
                                                 buffer.size());
      const subscriber::MessageHeader header = subscriber::decode_header(bytes);
      if (header.type == subscriber::MessageType::MeshInfo)
        websocket_subject =
            subscriber::decode_mesh_info(bytes.subspan(subscriber::kHeaderBytes), header.version).subject;
    }
  }
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  EXPECT_EQ(websocket_subject, "Actor2");

  ASSERT_EQ(removed.exit_code, 0) << removed.output << daemon.log();
  EXPECT_EQ(leaving.exit_code, 1);
  EXPECT_NE(leaving.output.find("subject Actor1 was removed from this daemon"), std::string::npos)
      << leaving.output;
  ASSERT_EQ(unnamed.exit_code, 0) << unnamed.output.substr(0, 2000) << daemon.log();
  test::expect_frames_follow_recording(read_capture(take_b_), test::frames_of(unnamed.output), -kApartMm);
}

}  // namespace
}  // namespace skinstream
