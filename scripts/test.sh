#!/usr/bin/env bash
# Installs what is missing, checks the layout of changed C++ lines (scripts/format-check.sh),
# builds everything and runs every test (unit, file, CLI), then a short fuzzing run of every
# parser (scripts/fuzz.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
export SKINSTREAM_DEPS_CHECKED=1  # the steps below need not check again
# The C++ lines changed since .clang-format came, as clang-format lays them out (seconds).
bash scripts/format-check.sh
# Explicit, so a build tree configured by run.sh (tests off) gets its tests back.
bash scripts/build.sh -DSKINSTREAM_BUILD_TESTS=ON -DSKINSTREAM_BUILD_BENCHMARKS=ON
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600
# Every parser fuzzed for a short while (10 s a target; FUZZ_SECONDS to change it).
bash scripts/fuzz.sh "${FUZZ_SECONDS:-10}"
