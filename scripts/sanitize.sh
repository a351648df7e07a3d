#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer: builds everything
# with -DSKINSTREAM_SANITIZE=address,undefined into build-asan/ (benchmarks left out) and runs
# every ctest test; the first report stops the test it happened in, which then fails. Extra
# arguments go to ctest (e.g. -R protocol). SANITIZE=thread builds build-tsan/ under
# ThreadSanitizer instead. TARGETS="server_tests daemon_tests" builds only those targets (and
# what they need) instead of everything. Takes longer than scripts/test.sh: the sanitized
# programs run slower. Compiled at -O1 with line tables only (-g1): file and line are what the
# reports need, and this code's templates compile faster so (the core's hot files keep their
# own -O2/-O3).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
launcher=()
if command -v ccache >/dev/null 2>&1; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
sanitizers=address,undefined
dir=build-asan
if [ "${SANITIZE:-}" = thread ]; then sanitizers=thread; dir=build-tsan; fi
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" "${launcher[@]}" \
  -DSKINSTREAM_SANITIZE="$sanitizers" -DSKINSTREAM_BUILD_TESTS=ON -DSKINSTREAM_BUILD_BENCHMARKS=OFF
targets=()
for t in ${TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$dir" -j "$(nproc)" "${targets[@]}"
export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1
export UBSAN_OPTIONS=print_stacktrace=1
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
ctest --test-dir "$dir" --output-on-failure -j "$(nproc)" --timeout 1800 "$@"
