// build_subject() runs a real program as the subject builder: small shell scripts standing in for
// `skinstream build-subject`, for its exit codes, its last words, its hangs; the real builder runs
// in the daemon's end-to-end tests (DaemonSubjectChanges).
#include "server/subjects/subject_builder.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

#include "support/test_data.h"

namespace skinstream::server {
namespace {

// A script as the builder: it is run as SCRIPT build-subject --capture C --out O [--mesh M].
std::string builder_script(const std::string& name, const std::string& body) {
  const std::string path = test::scratch_path(name);
  test::write_bytes(path, "#!/bin/sh\n" + body);
  EXPECT_EQ(chmod(path.c_str(), 0755), 0);
  return path;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(SubjectBuilder, ASuccessfulBuildKeepsItsReportAndTakesItsArgumentsInOrder) {
  const std::string script =
      builder_script("builder_ok.sh", "echo \"{\\\"args\\\": \\\"$*\\\"}\"\necho progress >&2\nexit 0\n");
  std::atomic<bool> cancel{false};
  const std::filesystem::path out = test::scratch_path("built_ok.sks");
  const SubjectBuildResult result =
      build_subject({script, "rom.c3d", out, "body.obj", std::chrono::seconds(30)}, cancel);
  EXPECT_TRUE(result.ok) << result.reason;
  EXPECT_GT(result.seconds, 0.0);
  EXPECT_EQ(read_text(result.report),
            "{\"args\": \"build-subject --capture rom.c3d --out " + out.string() + " --mesh body.obj\"}\n");
}

TEST(SubjectBuilder, AFailedBuildSaysItsExitCodeAndItsLastLine) {
  const std::string script = builder_script(
      "builder_fails.sh", "echo 'fitting...' >&2\necho 'not a body: 4 vertices' >&2\necho >&2\nexit 3\n");
  std::atomic<bool> cancel{false};
  const SubjectBuildResult result = build_subject(
      {script, "rom.c3d", test::scratch_path("built_fails.sks"), "", std::chrono::seconds(30)}, cancel);
  EXPECT_FALSE(result.ok);
  EXPECT_EQ(result.reason, "build-subject exited with 3: not a body: 4 vertices");
}

TEST(SubjectBuilder, ABuildThatHangsIsKilledAtItsTimeoutAndOneCancelledAtOnce) {
  const std::string script = builder_script("builder_hangs.sh", "exec sleep 30\n");
  std::atomic<bool> cancel{false};
  const auto start = std::chrono::steady_clock::now();
  const SubjectBuildResult late = build_subject(
      {script, "rom.c3d", test::scratch_path("built_hangs.sks"), "", std::chrono::seconds(1)}, cancel);
  EXPECT_FALSE(late.ok);
  EXPECT_EQ(late.reason, "the build took longer than 1 s");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  cancel.store(true);
  const SubjectBuildResult cancelled = build_subject(
      {script, "rom.c3d", test::scratch_path("built_cancelled.sks"), "", std::chrono::seconds(30)}, cancel);
  EXPECT_FALSE(cancelled.ok);
  EXPECT_EQ(cancelled.reason, "the build was cancelled (the daemon is stopping)");
}

TEST(SubjectBuilder, AProgramThatCannotRunIsAFailureWithTheReason) {
  std::atomic<bool> cancel{false};
  const SubjectBuildResult result = build_subject(
      {"/no/such/builder", "rom.c3d", test::scratch_path("built_none.sks"), "", std::chrono::seconds(30)},
      cancel);
  EXPECT_FALSE(result.ok);
  EXPECT_EQ(result.reason, "build-subject exited with 127: cannot run the subject builder (subject_builder)");
}

}  // namespace
}  // namespace skinstream::server
