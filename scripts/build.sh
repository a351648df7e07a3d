#!/usr/bin/env bash
# Installs what is missing (Debian 12), configures and builds skinstream into build/.
# Extra arguments go to CMake's configure step (e.g. -DSKINSTREAM_BUILD_BENCHMARKS=OFF).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# A compiler cache (installed by install-deps.sh): rebuilds, other checkouts of the same tree and
# the fuzz and sanitizer builds reuse what was compiled. Paths below the checkout are hashed
# relative to it and the build folder left out of the hash (-g would put it in), so two clones
# share entries.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
fi
# RelWithDebInfo's code (-O2 -DNDEBUG) without its debug information: the same program, compiled
# in two thirds of the CPU time (server/config.cpp 15 s against 22, tests/server/daemon_test.cpp
# 18 against 26). For a debugger: bash scripts/build.sh -DCMAKE_BUILD_TYPE=RelWithDebInfo.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" "${launcher[@]}" "$@"
cmake --build build -j "$(nproc)"
