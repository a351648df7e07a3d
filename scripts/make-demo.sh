#!/usr/bin/env bash
# Makes the demo subject the run command and the end-to-end tests use, from bundled data only:
#   OUT/rom_truth.c3d     20 s synthetic range-of-motion take (seed 1, the layout of
#                         replay_data/synthetic/*_seed1.c3d), every marker every frame
#   OUT/rest/mesh_000000.ply  the subdivided MakeHuman body (~53,500 vertices) at that take's
#                         first frame (the rest pose): the "artist's model"
#   OUT/subject.sksubj    markers (section 4) + the mesh registered, segmented and weighted
#                         (section 5), reference frame 0
#   OUT/live.c3d          the 2 s capture the end-to-end tests replay: replay_data/synthetic/jumprope_2s_seed1.c3d
#   OUT/medley.c3d        the 25 s capture the run command replays: punch, golf, jump rope, flex and
#                         breathing in turn (seed 1, made here rather than bundled: 2.3 MB saved)
# Usage: scripts/make-demo.sh SKINSTREAM_BINARY OUT_DIR [--no-medley]   (skips work already done)
# --no-medley: the subject and live.c3d only (the tests' fixture: no test replays the medley, and
# its synthesis is a sixth of the fixture's time, spent while the end-to-end tests wait).
set -euo pipefail
cli=${1:?usage: make-demo.sh SKINSTREAM_BINARY OUT_DIR [--no-medley]}
out=${2:?usage: make-demo.sh SKINSTREAM_BINARY OUT_DIR [--no-medley]}
medley=1
case "${3:-}" in
  "") ;;
  --no-medley) medley=0 ;;
  *) echo "usage: make-demo.sh SKINSTREAM_BINARY OUT_DIR [--no-medley]" >&2; exit 2 ;;
esac
root="$(cd "$(dirname "$0")/.." && pwd)"
mkdir -p "$out"
if [ ! -s "$out/rom_truth.c3d" ]; then
  "$cli" synth --motion rom --seconds 20 --seed 1 --body "$root/replay_data/makehuman" \
    --out "$out/rom.c3d" --truth "$out/rom_truth.c3d"
fi
if [ ! -s "$out/rest/mesh_000000.ply" ]; then
  "$cli" synth --motion rom --seconds 0.1 --seed 1 --subdivided --body "$root/replay_data/makehuman" \
    --out "$out/rest_markers.c3d" --mesh-out-every 1000 "$out/rest"
fi
if [ ! -s "$out/subject.sksubj" ] || [ "$out/subject.sksubj" -ot "$cli" ]; then
  "$cli" build-subject --capture "$out/rom_truth.c3d" --reference-frame 0 --mesh "$out/rest/mesh_000000.ply" \
    --marker-offset 4 --out "$out/subject.sksubj.tmp" > "$out/subject.json"
  mv "$out/subject.sksubj.tmp" "$out/subject.sksubj"
fi
cp "$root/replay_data/synthetic/jumprope_2s_seed1.c3d" "$out/live.c3d"
if [ "$medley" -eq 0 ]; then
  echo "make-demo: $out/subject.sksubj and $out/live.c3d ready (build report: $out/subject.json)"
  exit 0
fi
if [ ! -s "$out/medley.c3d" ] || [ "$out/medley.c3d" -ot "$cli" ]; then
  "$cli" synth --motion medley --seconds 25 --seed 1 --body "$root/replay_data/makehuman" --out "$out/medley.c3d.tmp.c3d" > /dev/null
  mv "$out/medley.c3d.tmp.c3d" "$out/medley.c3d"
fi
echo "make-demo: $out/subject.sksubj, $out/live.c3d and $out/medley.c3d ready (build report: $out/subject.json)"
