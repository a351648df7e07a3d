#!/usr/bin/env bash
# Installs what is missing, checks the layout of changed C++ lines (scripts/format-check.sh),
# builds everything and runs every test (unit, file, CLI), then a short fuzzing run of every
# parser (scripts/fuzz.sh). The last line says where the minutes went, phase by phase.
set -euo pipefail
cd "$(dirname "$0")/.."
phases=()
phase_started=$SECONDS
phase_done() {
  phases+=("$1 $((SECONDS - phase_started)) s")
  phase_started=$SECONDS
}

bash scripts/install-deps.sh
export SKINSTREAM_DEPS_CHECKED=1  # the steps below need not check again
phase_done install
# The C++ lines changed since .clang-format came, as clang-format lays them out (seconds).
bash scripts/format-check.sh
phase_done format
# Explicit, so a build tree configured by run.sh (tests off) gets its tests back.
bash scripts/build.sh -DSKINSTREAM_BUILD_TESTS=ON -DSKINSTREAM_BUILD_BENCHMARKS=ON
phase_done build

# The clang build of the fuzz targets runs beside the suite, at idle priority (SCHED_IDLE): the
# suite leaves about four tenths of the two cores unused, waiting on real time (sockets, timers,
# browsers), and an idle-priority compiler runs only when nothing else wants a core.
mkdir -p build
fuzz_build_log=build/fuzz-build.log
# In a process group of its own (setsid), so that a failing suite stops the whole build with it.
setsid chrt --idle 0 bash scripts/fuzz.sh --build-only > "$fuzz_build_log" 2>&1 &
fuzz_build=$!
trap 'kill -- -"$fuzz_build" 2>/dev/null || true' EXIT
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600
phase_done tests
if ! wait "$fuzz_build"; then
  tail -n 30 "$fuzz_build_log" >&2
  echo "test.sh: the fuzz build failed (last lines above; all of it in $fuzz_build_log)" >&2
  exit 1
fi
trap - EXIT
phase_done "rest of the fuzz build"
# Every parser fuzzed for a short while (10 s a target; FUZZ_SECONDS to change it).
bash scripts/fuzz.sh "${FUZZ_SECONDS:-10}"
phase_done fuzz
echo "test.sh: passed; $(IFS=,; echo "${phases[*]}" | sed 's/,/, /g'); total ${SECONDS} s"
