// skinstream-bench: end-to-end latency and cost of the real skinstreamd, fed over the network as
// in production: a Vicon DataStream replay server and N subscribers in this process, the daemon
// a child process (on loopback, or behind a shaped link with --link-mbit). Arguments, run, report.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>

#include "clients/bench/bench_options.h"
#include "clients/bench/bench_report.h"
#include "clients/bench/bench_run.h"

namespace {
// Ctrl-C or a kill: the run unwinds, stopping the daemon and removing the shaped link.
std::atomic<bool> stop_requested{false};
void request_stop(int) { stop_requested = true; }
}  // namespace

int main(int argc, char** argv) {
  skinstream::bench::BenchOptions options;
  if (const auto exit_code = skinstream::bench::parse_bench_options(argc, argv, options)) return *exit_code;
  // The replay server and subscribers in this process log to stderr: stdout is the report,
  // JSON with --json, which a peer of the replay server once broke with a warning.
  spdlog::set_default_logger(spdlog::stderr_color_mt("bench"));
  std::signal(SIGINT, request_stop);
  std::signal(SIGTERM, request_stop);
  try {
    skinstream::bench::print_report(skinstream::bench::run_bench(options, stop_requested), options.json);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-bench: error: %s\n", e.what());
    return stop_requested ? 130 : 1;
  }
}
