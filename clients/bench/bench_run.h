#pragma once
// One benchmark run: the Vicon DataStream replay server in this process, the real skinstreamd as
// a child (on loopback, or in a network namespace behind a shaped link), N subscribers of the
// C++ client library in this process. Returns the report (see bench_report.h for its keys).
#include <atomic>
#include <nlohmann/json.hpp>

#include "clients/bench/bench_options.h"

namespace skinstream::bench {

// Throws std::runtime_error (or FileError) with a one-line reason; the daemon's log follows
// when it failed to start. Returns early, by throwing, once `stop` is set (SIGINT, SIGTERM), so
// the daemon, the subscribers and the shaped link are all taken down on the way out.
nlohmann::json run_bench(const BenchOptions& options, const std::atomic<bool>& stop);

}  // namespace skinstream::bench
