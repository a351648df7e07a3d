// skinstream-bench: end-to-end latency and cost of the real skinstreamd, fed over the network as
// in production: a Vicon DataStream replay server and N subscribers in this process, the daemon
// a child process (on loopback, or behind a shaped link with --link-mbit). Arguments, run, report.
#include <cstdio>
#include <exception>

#include "clients/bench/bench_options.h"
#include "clients/bench/bench_report.h"
#include "clients/bench/bench_run.h"

int main(int argc, char** argv) {
  skinstream::bench::BenchOptions options;
  if (const auto exit_code = skinstream::bench::parse_bench_options(argc, argv, options)) return *exit_code;
  try {
    skinstream::bench::print_report(skinstream::bench::run_bench(options), options.json);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-bench: error: %s\n", e.what());
    return 1;
  }
}
