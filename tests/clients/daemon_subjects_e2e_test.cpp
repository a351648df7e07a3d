// Several actors on one stage, with the real programs on loopback: skinstream-replay streams two
// recordings of one marker template as the Vicon subjects Actor1 and Actor2, and skinstreamd
// follows them by name. A stage grows past one machine by running one daemon per group of
// subjects, each a separate client of the same Vicon stream.
#include <gtest/gtest.h>

#include <thread>

#include "protocol/files/capture_file.h"
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

}  // namespace
}  // namespace skinstream
