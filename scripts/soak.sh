#!/usr/bin/env bash
# The soak: MINUTES of the demo body at 120 Hz through the real skinstreamd to 8 good
# subscribers, while hostile peers (stalled TCP and WebSocket subscribers, garbage and Hello
# floods, churn from 127.0.0.2-9) connect and leave in waves: WAVE_SECONDS on, CALM_SECONDS off.
# Prints skinstream-bench's JSON report: the good subscribers' frames/s and latency, drops, the
# daemon's RSS every minute, and per wave its RSS before, at the peak and after the calm.
# Usage: scripts/soak.sh MINUTES [BUILD_DIR] [WAVE_SECONDS] [CALM_SECONDS]
#   (BUILD_DIR defaults to build; its demo/ comes from scripts/make-demo.sh)
set -euo pipefail
minutes=${1:?usage: soak.sh MINUTES [BUILD_DIR] [WAVE_SECONDS] [CALM_SECONDS]}
build=${2:-build}
wave=${3:-60}
calm=${4:-60}
for needed in "$build/bin/skinstream-bench" "$build/bin/skinstreamd" "$build/demo/subject.sksubj" "$build/demo/live.c3d"; do
  [ -e "$needed" ] || { echo "soak.sh: $needed is missing (build skinstream-bench and skinstreamd; scripts/make-demo.sh)" >&2; exit 1; }
done
exec "$build/bin/skinstream-bench" --subject "$build/demo/subject.sksubj" --recording "$build/demo/live.c3d" \
  --subscribers 8 --seconds "$((minutes * 60))" --hostile-waves --wave-seconds "$wave" --calm-seconds "$calm" --json
