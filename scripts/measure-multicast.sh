#!/usr/bin/env bash
# Measures the multicast parameter stream between network namespaces on one bridge: skinstreamd
# replaying the demo at full rate in one namespace, RECEIVERS skinstream-sub --multicast in
# others, each taking FRAMES frames. Prints each receiver's JSON summary, the daemon's multicast
# counters and its CPU over the receivers' run. LOSS=10 drops that percentage of the first
# receiver's datagrams, the offer's too (nftables); EVALUATE=1 has the receivers evaluate the
# vertices; OFFER_MBIT=0 turns the daemon's offer of MeshInfo and the Model off (the receivers
# then fetch them over TCP; 20 Mbit/s by default). Needs root, iproute2 and the build
# (scripts/build.sh, demo).
#   bash scripts/measure-multicast.sh [RECEIVERS] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
receivers=${1:-1}
frames=${2:-1200}
loss=${LOSS:-0}
offer_mbit=${OFFER_MBIT:-20}
stem="skmm$$"
group=239.255.77.1:9577
hosts=()
cleanup() {
  [ -n "${daemon_pid:-}" ] && kill "$daemon_pid" 2>/dev/null && wait "$daemon_pid" 2>/dev/null || true
  for h in "${hosts[@]}"; do ip netns del "$h" 2>/dev/null || true; done
  ip netns del "$stem-lan" 2>/dev/null || true
  rm -rf "$scratch"
}
scratch=$(mktemp -d)
trap cleanup EXIT
ip netns add "$stem-lan"
ip -n "$stem-lan" link add lan type bridge mcast_snooping 0
ip -n "$stem-lan" link set lan up
for i in $(seq 0 "$receivers"); do
  h="$stem-h$i"
  hosts+=("$h")
  ip netns add "$h"
  ip link add "port$i" netns "$stem-lan" type veth peer name eth0 netns "$h"
  ip -n "$stem-lan" link set "port$i" master lan up
  ip -n "$h" addr add "10.215.0.$((i + 1))/24" dev eth0
  ip -n "$h" link set eth0 up
  ip -n "$h" link set lo up
done
ip netns exec "$stem-h0" build/bin/skinstreamd --subject build/demo/subject.sksubj --replay build/demo/live.c3d --loop \
  --bind 0.0.0.0 --http-port 8480 --sub-port 8481 --multicast "$group" --multicast-interface 10.215.0.1 \
  --multicast-offer-mbit "$offer_mbit" --ports-file "$scratch/ports.json" > "$scratch/daemon.log" 2>&1 &
daemon_pid=$!
while [ ! -f "$scratch/ports.json" ]; do sleep 0.1; done
if [ "$loss" != 0 ]; then
  ip netns exec "$stem-h1" nft add table inet loss
  ip netns exec "$stem-h1" nft add chain inet loss input '{ type filter hook input priority 0; }'
  ip netns exec "$stem-h1" nft add rule inet loss input udp dport '{ 9577, 9578 }' numgen random mod 100 '<' "$loss" counter drop
fi
cpu_ticks() { awk '{print $14 + $15}' "/proc/$daemon_pid/stat"; }
health() { ip netns exec "$stem-h0" curl -s http://127.0.0.1:8480/health; }
sleep 2
before=$(cpu_ticks); started=$(date +%s.%N)
for i in $(seq 1 "$receivers"); do
  ip netns exec "$stem-h$i" build/bin/skinstream-sub 10.215.0.1:8481 --multicast "$group" --multicast-interface "10.215.0.$((i + 1))" \
    --json --frames "$frames" ${EVALUATE:+--evaluate} $([ "$offer_mbit" = 0 ] && echo --multicast-no-offer) > "$scratch/receiver$i.json" 2> "$scratch/receiver$i.err" &
done
wait $(jobs -p | grep -v "^$daemon_pid$")
after=$(cpu_ticks); ended=$(date +%s.%N)
for i in $(seq 1 "$receivers"); do echo "receiver $i: $(tail -1 "$scratch/receiver$i.json")"; cat "$scratch/receiver$i.err"; done
[ "$loss" != 0 ] && ip netns exec "$stem-h1" nft list table inet loss | grep counter
echo "daemon multicast: $(health | python3 -c 'import json,sys; print(json.dumps([s.get("multicast") for s in json.load(sys.stdin)["subjects"]]))')"
python3 -c "import os; t=float('$ended')-float('$started'); print(f'daemon CPU over the receivers\' {t:.1f} s: {($after-$before)/os.sysconf(\"SC_CLK_TCK\")/t*100:.1f}% of one core')"
