#!/usr/bin/env bash
# Installs what is missing, builds everything and runs every test (unit, file, CLI).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600
