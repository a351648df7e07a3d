#pragma once
// One benchmark run: the Vicon DataStream replay server in this process, the real skinstreamd as
// a child (on loopback, or in a network namespace behind a shaped link), N subscribers of the
// C++ client library in this process. Returns the report (see bench_report.h for its keys).
#include <nlohmann/json.hpp>

#include "clients/bench/bench_options.h"

namespace skinstream::bench {

// Throws std::runtime_error (or FileError) with a one-line reason; the daemon's log follows
// when it failed to start.
nlohmann::json run_bench(const BenchOptions& options);

}  // namespace skinstream::bench
