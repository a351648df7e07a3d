#!/usr/bin/env bash
# The main job on bundled data: installs what is missing, builds, makes the demo subject
# (markers + the ~53,500-vertex MakeHuman mesh), builds the web viewer, then runs skinstreamd
# replaying a bundled 350-marker capture in a loop. Open the printed URL to watch the deforming
# body; Ctrl-C stops it. RUN_SECONDS=N stops it after N seconds (scripts, CI).
# RUN_CAPTURE=TAKE.c3d serves a real capture instead: the body template is fitted to its actor
# first (skinstream build-subject --mesh the template; a few seconds), e.g.
#   RUN_CAPTURE=replay_data/cmu/85_12.c3d bash scripts/run.sh
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF
bash clients/web/build.sh build/web
http_port=${HTTP_PORT:-8480}
sub_port=${SUB_PORT:-8481}
if [ -n "${RUN_CAPTURE:-}" ]; then
  mkdir -p build/actor
  subject=build/actor/$(basename "${RUN_CAPTURE%.*}").sksubj
  echo "== fitting the body template to the actor of $RUN_CAPTURE (report: $subject.json)"
  build/bin/skinstream build-subject --capture "$RUN_CAPTURE" --mesh replay_data/makehuman/makehuman_hm08_body_only.obj \
    --out "$subject" > "$subject.json"
  echo
  echo "== skinstreamd: replaying $RUN_CAPTURE (looped) with the fitted actor"
  echo "== open http://localhost:${http_port}/ in a browser (TCP subscribers: port ${sub_port})"
  echo
  cmd=(build/bin/skinstreamd --subject "$subject" --replay "$RUN_CAPTURE" --loop
       --web-root build/web --http-port "$http_port" --sub-port "$sub_port")
  if [ -n "${RUN_SECONDS:-}" ]; then
    exec timeout --signal=INT --preserve-status "$RUN_SECONDS" "${cmd[@]}"
  fi
  exec "${cmd[@]}"
fi
bash scripts/make-demo.sh build/bin/skinstream build/demo
echo
echo "== skinstreamd: replaying build/demo/medley.c3d (350 markers, 120 Hz, 25 s: punch, golf, jump rope, flex, breathing; looped)"
echo "== open http://localhost:${http_port}/ in a browser (TCP subscribers: port ${sub_port};"
echo "   metrics: http://localhost:${http_port}/metrics)"
echo
cmd=(build/bin/skinstreamd --subject build/demo/subject.sksubj --replay build/demo/medley.c3d --loop
     --web-root build/web --http-port "$http_port" --sub-port "$sub_port")
if [ -n "${RUN_SECONDS:-}" ]; then
  exec timeout --signal=INT --preserve-status "$RUN_SECONDS" "${cmd[@]}"
fi
exec "${cmd[@]}"
