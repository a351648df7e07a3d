#include "server/subjects/subject_builder.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "protocol/printable_text.h"

namespace skinstream::server {
namespace {

// Below the daemon's frame threads (nice 0), which preempt it at once, level with the take
// recorder. At nice 19 it starved beside a browser on both cores: a 3 s calibration's build took
// 187 s instead of 4-17 s (docs/method-notes.md, "Swapping a subject between two frames").
constexpr int kBuilderNice = 10;

// The last non-empty line of a file, made printable and bounded: what a failed build said.
std::string last_line_of(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return printable_text(last, 400);
}

}  // namespace

std::string default_subject_builder() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path beside = self.parent_path() / "skinstream";
    if (::access(beside.c_str(), X_OK) == 0) return beside.string();
  }
  return "skinstream";
}

SubjectBuildResult build_subject(const SubjectBuildRequest& request, const std::atomic<bool>& cancel) {
  SubjectBuildResult result;
  result.report = request.out.string() + ".json";
  const std::filesystem::path log = request.out.string() + ".log";
  std::vector<std::string> words = {request.builder,          "build-subject", "--capture",
                                    request.capture.string(), "--out",         request.out.string()};
  if (!request.mesh.empty()) words.insert(words.end(), {"--mesh", request.mesh});
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);

  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    result.reason = "cannot start the builder (fork failed)";
    return result;
  }
  if (pid == 0) {
    // The child: never outlives the daemon, holds none of its sockets, runs below the frame threads.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    setpriority(PRIO_PROCESS, 0, kBuilderNice);
    const int out = ::open(result.report.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (out < 0 || err < 0) _exit(126);
    dup2(out, STDOUT_FILENO);
    dup2(err, STDERR_FILENO);
    close_range(3, ~0U, 0);
    execvp(argv[0], argv.data());
    // Nothing that allocates between fork and exec (another thread may hold the heap's lock).
    static constexpr char kSaid[] = "cannot run the subject builder (subject_builder)\n";
    (void)!::write(STDERR_FILENO, kSaid, sizeof kSaid - 1);
    _exit(127);
  }
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    const bool late = std::chrono::steady_clock::now() - start > request.timeout;
    if (done < 0 || cancel.load() || late) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      result.reason = cancel.load()
                          ? "the build was cancelled (the daemon is stopping)"
                          : "the build took longer than " + std::to_string(request.timeout.count()) + " s";
      return result;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    result.ok = true;
    return result;
  }
  const std::string said = last_line_of(log);
  result.reason = "build-subject " +
                  (WIFEXITED(status) ? "exited with " + std::to_string(WEXITSTATUS(status))
                                     : "was killed by signal " + std::to_string(WTERMSIG(status))) +
                  (said.empty() ? "" : ": " + said);
  return result;
}

}  // namespace skinstream::server
