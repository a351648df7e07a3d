#!/usr/bin/env bash
# The main job on the bundled data: build a subject model from one real take, then delete
# seeded gaps from another take and fill them online, side by side with the baselines.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF
out=build/run
mkdir -p "$out"
echo "== subject model from replay_data/cmu/85_12.c3d"
build/bin/skinstream build-subject --capture replay_data/cmu/85_12.c3d --out "$out/cmu85.subject" \
  --surface-out "$out/cmu85_marker_surface.obj"
echo "== gap filling on replay_data/cmu/85_02.c3d (seeded gaps, every method)"
build/bin/skinstream eval-fill --capture replay_data/cmu/85_02.c3d --train replay_data/cmu/85_12.c3d --ablations
echo "== outputs in $out (marker surface OBJ, subject file)"
