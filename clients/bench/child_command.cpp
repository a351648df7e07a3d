#include "clients/bench/child_command.h"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <stdexcept>

namespace skinstream::bench {

CommandResult run_command(const std::vector<std::string>& argv, const CommandOptions& options) {
  if (argv.empty()) throw std::runtime_error("run_command: no program");
  // Made before fork: the bench is threaded, and the child of a threaded process must not
  // allocate (another thread may hold the heap's lock).
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  static constexpr char kNotFound[] = ": not found\n";
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) {
    close(pipe_fds[0]);
    close(pipe_fds[1]);
    throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    if (options.nice > 0) setpriority(PRIO_PROCESS, 0, options.nice);
    if (options.idle) {
      const sched_param none{};
      sched_setscheduler(0, SCHED_IDLE, &none);
    }
    if (options.stdin_fd >= 0) dup2(options.stdin_fd, STDIN_FILENO);
    dup2(pipe_fds[1], STDOUT_FILENO);
    dup2(pipe_fds[1], STDERR_FILENO);
    execvp(args[0], args.data());
    (void)!::write(STDERR_FILENO, args[0], std::strlen(args[0]));
    (void)!::write(STDERR_FILENO, kNotFound, sizeof kNotFound - 1);
    _exit(127);
  }
  close(pipe_fds[1]);
  CommandResult result;
  const auto give_up = std::chrono::steady_clock::now() + options.limit;
  std::array<char, 4096> buffer;
  for (;;) {
    if (options.limit.count() > 0) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(give_up - std::chrono::steady_clock::now())
              .count();
      pollfd ready{pipe_fds[0], POLLIN, 0};
      if (left <= 0 || poll(&ready, 1, static_cast<int>(left)) <= 0) {
        kill(pid, SIGKILL);
        result.timed_out = true;
        break;
      }
    }
    const ssize_t n = read(pipe_fds[0], buffer.data(), buffer.size());
    if (n <= 0) break;
    result.output.append(buffer.data(), static_cast<size_t>(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace skinstream::bench
