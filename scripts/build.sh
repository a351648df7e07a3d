#!/usr/bin/env bash
# Installs what is missing (Debian 12), configures and builds skinstream into build/.
# Extra arguments go to CMake's configure step (e.g. -DSKINSTREAM_BUILD_BENCHMARKS=OFF).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@"
cmake --build build -j "$(nproc)"
