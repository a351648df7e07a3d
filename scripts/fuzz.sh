#!/usr/bin/env bash
# Fuzzes every parser: builds the libFuzzer targets of tests/fuzz/ with clang, AddressSanitizer
# and UndefinedBehaviorSanitizer into build-fuzz/, then runs each, one per processor at a time,
# for SECONDS (default 10) on its corpus (build-fuzz/fuzz/corpus/TARGET, seeded from the real
# files the first time and kept between runs, so coverage grows run after run). One JSON line per target:
#   {"target":"c3d","seconds":10,"executions":123456,"findings":0,"corpus":321}
# A finding is a crash, a sanitizer report, an input over 10 s or over 2 GB of memory; its input
# is kept in build-fuzz/fuzz/findings/TARGET/ (replay it: build-fuzz/bin/fuzz_TARGET FILE).
# Exits non-zero when any target found anything. Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
# FUZZ_RUNS=N also stops each target after N executions (a long run: FUZZ_RUNS=10000000 with
# SECONDS as the cap on each target). scripts/fuzz.sh --build-only: the clang build alone (the
# test command runs it beside the suite).
set -euo pipefail
cd "$(dirname "$0")/.."
build_only=0
if [ "${1:-}" = "--build-only" ]; then
  build_only=1
  shift
fi
seconds=${1:-10}
shift || true
runs=()
if [ -n "${FUZZ_RUNS:-}" ]; then runs=(-runs="$FUZZ_RUNS"); fi
bash scripts/install-deps.sh >&2
launcher=()
# As scripts/build.sh: paths hashed relative to the checkout, so a fresh clone (CI) reuses what
# another checkout's fuzz build compiled instead of compiling the whole fuzz build again.
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
fi
# -O2 as RelWithDebInfo, with line tables only for the sanitizers' stack traces: full debug
# information roughly doubles what the compiler writes and is not read here.
# File by file, not in unity groups: a group pulls a whole group of runtime files into a fuzz
# target, the deformer among them, whose call into the multiversioned evaluator clang 14 does
# not link (the evaluator's clones are named apart from the header's declaration).
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" -DSKINSTREAM_FUZZ=ON -DSKINSTREAM_UNITY_BUILD=OFF \
  -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF >&2
cmake --build build-fuzz -j "$(nproc)" --target skinstream_fuzz >&2
if [ "$build_only" -eq 1 ]; then exit 0; fi

# The made seeds come from the test build (uninstrumented; tests/CMakeLists.txt).
make_seeds=build/bin/fuzz_make_seeds
if [ ! -f build/build.ninja ] || ! grep -q "SKINSTREAM_BUILD_TESTS:BOOL=ON" build/CMakeCache.txt; then
  bash scripts/build.sh -DSKINSTREAM_BUILD_TESTS=ON >&2
fi
cmake --build build -j "$(nproc)" --target fuzz_make_seeds >&2
fuzz=$PWD/build-fuzz/fuzz
if [ ! -f "$fuzz/seeds/done" ] || [ "$make_seeds" -nt "$fuzz/seeds/done" ]; then
  "$make_seeds" "$fuzz/seeds" >&2
  touch "$fuzz/seeds/done"
fi
mkdir -p "$fuzz/tmp"
export TMPDIR=$fuzz/tmp  # where the file readers' targets write each input
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then mapfile -t targets < "$fuzz/targets.txt"; fi

# One target per processor at a time (each is single-threaded); a target's line is printed when
# it ends, so lines come in the order the targets finish.
fuzz_one() {
  local target=$1
  local corpus=$fuzz/corpus/$target findings=$fuzz/findings/$target log=$fuzz/$target.log
  mkdir -p "$corpus"
  rm -rf "$findings"
  mkdir -p "$findings"
  if [ -z "$(ls -A "$corpus")" ]; then  # first run: the real files and the made seeds
    while IFS= read -r seed; do
      [ -n "$seed" ] && cp "$seed" "$corpus/$(basename "$seed")"
    done < "$fuzz/$target.seeds"
    if [ -d "$fuzz/seeds/$target" ]; then cp "$fuzz/seeds/$target"/* "$corpus/"; fi
  fi
  local status=0 started
  started=$(date +%s)
  build-fuzz/bin/fuzz_"$target" -max_total_time="$seconds" "${runs[@]}" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$findings/" "$corpus" > "$log" 2>&1 || status=$?
  local executions found
  executions=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -1)
  found=$(find "$findings" -type f | wc -l)
  if [ "$status" -ne 0 ] && [ "$found" -eq 0 ]; then found=1; fi  # stopped by something that left no input
  printf '{"target":"%s","seconds":%s,"executions":%s,"findings":%s,"corpus":%s}\n' \
    "$target" "$(( $(date +%s) - started ))" "${executions:-0}" "$found" "$(find "$corpus" -type f | wc -l)"
  if [ "$found" -ne 0 ]; then
    echo "fuzz: $target: see $log and $findings/" >&2
    grep -m 3 -E "ERROR|runtime error|deadly signal|Abort" "$log" >&2 || true
    return 1
  fi
}

failed=0
running=0
for target in "${targets[@]}"; do
  if [ "$running" -ge "$(nproc)" ]; then
    wait -n || failed=1
    running=$((running - 1))
  fi
  fuzz_one "$target" &
  running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
  wait -n || failed=1
  running=$((running - 1))
done
rm -rf "$fuzz/tmp"
exit $failed
