#!/usr/bin/env bash
# Builds the runtime image (Dockerfile) and checks it, the step before each stop where a Docker
# engine is present:
#   - its size, printed as one JSON line, at most IMAGE_MAX_MB (400) megabytes;
#   - a container with its ports published on loopback only (free ports Docker picks): GET /health
#     answers, GET / and /app.js serve the page, a TCP subscriber receives Frame messages,
#     /metrics counts frames published and received frames rising, the daemon runs as a user other than root, and
#     the image's HEALTHCHECK reports the container healthy.
# The container is stopped and removed, the image kept. Any failure: exit 1 with one line saying why.
# Usage: bash scripts/image.sh [TAG]   (default skinstream:latest)
#   IMAGE_NICE=N      niceness of the compile inside the build (default 15; 0 for full speed)
#   IMAGE_BUILD_ARGS  more `docker build` arguments, e.g. "--build-arg SKINSTREAM_CPU_LEVEL=x86-64"
set -euo pipefail
cd "$(dirname "$0")/.."
tag=${1:-skinstream:latest}
max_mb=${IMAGE_MAX_MB:-400}
build_nice=${IMAGE_NICE:-15}
name=skinstream-image-check-$$
work=$(mktemp -d)
container=""

cleanup() {
  if [ -n "$container" ]; then docker rm -f "$container" >/dev/null 2>&1 || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  if [ -n "$container" ]; then
    echo "--- last lines of the container's log:" >&2
    docker logs --tail 15 "$container" 2>&1 | sed 's/^/    /' >&2 || true
  fi
  echo "image.sh: $*" >&2
  exit 1
}

command -v docker >/dev/null || fail "docker not found"
docker info >/dev/null 2>&1 || fail "no Docker engine answers ('docker info' fails): nothing built"
command -v curl >/dev/null || fail "curl not found (apt-get install curl)"

# The compile runs in the engine, not under this client: the Dockerfile's SKINSTREAM_BUILD_NICE
# lowers it there; nice on the client too, where there is one.
nice_cmd=()
if command -v nice >/dev/null; then nice_cmd=(nice -n 15); fi
echo "image.sh: building $tag (log: docker build output below on failure)"
# shellcheck disable=SC2086  # IMAGE_BUILD_ARGS is split into arguments on purpose
if ! "${nice_cmd[@]}" docker build --build-arg SKINSTREAM_BUILD_NICE="$build_nice" ${IMAGE_BUILD_ARGS:-} \
     -t "$tag" . > "$work/build.log" 2>&1; then
  tail -n 25 "$work/build.log" | sed 's/^/    /' >&2
  fail "docker build failed (last lines above)"
fi

bytes=$(docker image inspect -f '{{.Size}}' "$tag") || fail "cannot read the size of $tag"
megabytes=$(awk -v b="$bytes" 'BEGIN { printf "%.1f", b / 1e6 }')
echo "{\"image\":\"$tag\",\"bytes\":$bytes,\"megabytes\":$megabytes,\"limit_megabytes\":$max_mb}"
if [ "$bytes" -gt $((max_mb * 1000000)) ]; then
  fail "$tag is $megabytes MB, $(awk -v b="$bytes" -v m="$max_mb" 'BEGIN { printf "%.1f", b / 1e6 - m }') MB over the $max_mb MB limit"
fi

user=$(docker image inspect -f '{{.Config.User}}' "$tag")
case "$user" in
  "" | root | 0 | 0:*) fail "$tag runs as root (USER '${user}')" ;;
esac

container=$(docker run -d --name "$name" -p 127.0.0.1::8480 -p 127.0.0.1::8481 "$tag") \
  || fail "docker run failed"
http_port=$(docker port "$container" 8480/tcp | head -n 1 | sed 's/.*://')
sub_port=$(docker port "$container" 8481/tcp | head -n 1 | sed 's/.*://')
{ [ -n "$http_port" ] && [ -n "$sub_port" ]; } || fail "no published ports for 8480 and 8481"
base=http://127.0.0.1:$http_port

running() { [ "$(docker inspect -f '{{.State.Running}}' "$container" 2>/dev/null)" = true ]; }
# /health: the daemon has loaded and checked its subject and listens.
for _ in $(seq 1 120); do
  running || fail "the daemon exited (code $(docker inspect -f '{{.State.ExitCode}}' "$container")) before /health answered"
  if curl -fsS --max-time 3 "$base/health" -o "$work/health.json" 2>/dev/null; then break; fi
  sleep 1
done
[ -s "$work/health.json" ] || fail "GET /health did not answer within 120 s"
grep -q '"status":"ok"' "$work/health.json" || fail "GET /health answered without \"status\":\"ok\""

# The page and its script.
curl -fsS --max-time 5 "$base/" -o "$work/index.html" || fail "GET / failed"
grep -qi '<html' "$work/index.html" || fail "GET / served no HTML page"
curl -fsS --max-time 5 "$base/app.js" -o "$work/app.js" || fail "GET /app.js failed"
[ -s "$work/app.js" ] || fail "GET /app.js served nothing"

# A TCP subscriber (protocol version 1, markers only: wants = markers | no mesh): the messages it
# receives until the first Frame (type 3). Header: magic SKSF, u16 version, u16 type, u32 bytes.
read_bytes() { timeout 10 dd bs="$1" count=1 iflag=fullblock status=none <&3; }
exec 3<>"/dev/tcp/127.0.0.1/$sub_port" || fail "cannot connect to the subscriber port ($sub_port)"
printf 'SKSF\x01\x00\x01\x00\x04\x00\x00\x00\x0c\x00\x00\x00' >&3
types=()
for _ in $(seq 1 20); do
  read -r -a b <<< "$(read_bytes 12 | od -An -tu1 -v | tr '\n' ' ')"
  [ "${#b[@]}" -eq 12 ] || fail "the subscriber port closed or went quiet after messages: ${types[*]:-none}"
  [ "${b[0]} ${b[1]} ${b[2]} ${b[3]}" = "83 75 83 70" ] || fail "the subscriber port sent a message without the SKSF magic"
  type=$((b[6] + 256 * b[7]))
  length=$((b[8] + (b[9] << 8) + (b[10] << 16) + (b[11] << 24)))
  types+=("$type")
  [ "$type" -eq 3 ] && break
  if [ "$length" -gt 0 ]; then read_bytes "$length" > /dev/null || fail "the subscriber port closed mid-message"; fi
done
exec 3>&-
[ "${types[${#types[@]}-1]}" -eq 3 ] || fail "no Frame among the first ${#types[@]} subscriber messages (types ${types[*]})"

# The subscriber above was published frames, and the replay keeps coming in. The daemon hands
# frames to its publishers only while someone subscribes, so with nobody left the published
# count stands still: what keeps rising is the frames received from the source.
counter() {
  curl -fsS --max-time 5 "$base/metrics" |
    awk -v name="$1" 'index($1, name "{") == 1 || $1 == name { n += $NF } END { printf "%d", n }'
}
published=$(counter skinstream_frames_published_total) || fail "GET /metrics failed"
[ "$published" -gt 0 ] || fail "skinstream_frames_published_total is 0 after the subscriber's Frame messages"
first=$(counter skinstream_frames_received_total) || fail "GET /metrics failed"
sleep 2
second=$(counter skinstream_frames_received_total) || fail "GET /metrics failed"
[ "$second" -gt "$first" ] || fail "skinstream_frames_received_total did not rise in 2 s ($first, then $second)"

# The image's own HEALTHCHECK (every 10 s).
for _ in $(seq 1 45); do
  health=$(docker inspect -f '{{if .State.Health}}{{.State.Health.Status}}{{else}}none{{end}}' "$container")
  case "$health" in
    healthy) break ;;
    none) fail "$tag has no HEALTHCHECK" ;;
    unhealthy) fail "the image's HEALTHCHECK reports unhealthy" ;;
  esac
  sleep 2
done
[ "$health" = healthy ] || fail "the image's HEALTHCHECK did not report healthy within 90 s ($health)"

docker rm -f "$container" > /dev/null || fail "cannot remove the container $name"
container=""
echo "image.sh: $tag ($megabytes MB) ok: /health, the page, a TCP subscriber's Frame messages" \
     "(after types ${types[*]}), $published frames published, frames received $first -> $second in 2 s, user $user, healthy"
