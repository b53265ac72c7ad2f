#!/usr/bin/env bash
# A 16 km² world (bench/world16.lua: big.lua's forest over 4 km x 4 km, 256 tiles, ~1.7 M
# trees, shared variants), grown twice on this machine, in one run:
#   L. without Ray: `pge run --variants-out` (every core), then the tiles dealt in turn to
#      two `pge run --tile I,J --tile ... --out-dir --variants --threads 1` processes at
#      once (as pge-world's tasks run them);
#   R. pge-world on the local two-node Ray cluster of .ci/ray (a head and a worker node on
#      127.0.0.1, one CPU each), shared variants, one task per node (--tiles-per-task 128:
#      the same two processes' work), the world directory seen by both (one machine);
#   R16. the same with pge-world's default batches (at most 16 tiles a task: 16 tasks).
# Every tile and both variants files of R and R16 are checked equal, byte for byte, to L's;
# prints R / L and R16 / L, wall times, and the load before and after.
# Usage (from the repository root, after .ci/ray or with ray and pge-world installed):
#   integrations/ray/bench/world16.sh [WORKDIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
script=$root/integrations/ray/bench/world16.lua
work=${1:-$(mktemp -d /tmp/pgeworld16.XXXXXX)}
venv=${VENV:-$root/target/ray-venv}
export PATH="$root/target/release:$venv/bin:$PATH" RAY_USAGE_STATS_ENABLED=0
mkdir -p "$work"
now() { date +%s.%N; }
since() { echo "$(now) - $1" | bc; }
echo "machine: $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GB, $(uname -sr)"
echo "load before: $(uptime)"

# L: no Ray.
rm -rf "$work/local" && mkdir -p "$work/local/tiles"
pge tiles "$script" | grep -o '"i":[0-9]*,"j":[0-9]*' |
  sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/--tile \1,\2/' |
  awk '{ b[NR % 2] = b[NR % 2] " " $0 } END { print b[0]; print b[1] }' >"$work/batches"
t0=$(now)
pge run "$script" --variants-out "$work/local" -q
variants=$(since "$t0")
export SCRIPT=$script WORK=$work
# shellcheck disable=SC2016
xargs -P 2 -L 1 sh -c 'pge run "$SCRIPT" "$@" --variants "$WORK/local" --threads 1 -q --out-dir "$WORK/local/tiles"' sh \
  <"$work/batches"
local_time=$(since "$t0")
bytes=$(du -cb "$work"/local/tiles/*.glb | tail -1 | cut -f1)
echo "L. no Ray: ${local_time}s (variants ${variants}s), $(ls "$work"/local/tiles | wc -l) tiles," \
  "$bytes bytes of tiles"

# 13 distinct free ports (bound all at once): the head's GCS port, then 6 per node.
read -r -a free <<<"$(python3 -c '
import socket
s = [socket.socket() for _ in range(13)]
for x in s: x.bind(("127.0.0.1", 0))
print(" ".join(str(x.getsockname()[1]) for x in s))')"
ports() { # the ports of node $1 (0: head, 1: worker)
  local b=$((1 + 6 * $1))
  echo "--node-manager-port=${free[b]} --object-manager-port=${free[b + 1]}" \
    "--metrics-export-port=${free[b + 2]} --dashboard-agent-listen-port=${free[b + 3]}" \
    "--dashboard-agent-grpc-port=${free[b + 4]} --runtime-env-agent-port=${free[b + 5]}"
}
temp=$(mktemp -d /tmp/pgerayw.XXXXXX)
head_port=${free[0]}
cleanup() { ray stop --force >/dev/null 2>&1 || true; rm -rf "$temp"; }
trap cleanup EXIT
# shellcheck disable=SC2046
ray start --head --node-ip-address=127.0.0.1 --port="$head_port" --num-cpus=1 \
  --object-store-memory=600000000 --include-dashboard=false --temp-dir="$temp" \
  --disable-usage-stats $(ports 0) >/dev/null
# shellcheck disable=SC2046
ray start --address="127.0.0.1:$head_port" --node-ip-address=127.0.0.1 --num-cpus=1 \
  --object-store-memory=600000000 $(ports 1) >/dev/null

same() { # the world $1 holds L's variants and tiles, byte for byte
  for f in variants.bin variants.json; do
    cmp -s "$work/local/$f" "$1/$f" || { echo "$1: $f differs"; exit 1; }
  done
  for f in "$work"/local/tiles/*.glb; do
    cmp -s "$f" "$1/tiles/$(basename "$f")" || { echo "$1: tile $(basename "$f") differs"; exit 1; }
  done
  [ "$(ls "$1/tiles" | wc -l)" = "$(ls "$work/local/tiles" | wc -l)" ] || { echo "$1: tile count"; exit 1; }
  pge world verify "$1" >/dev/null
}

rm -rf "$work/ray"
t0=$(now)
pge-world "$script" --out "$work/ray" --address "127.0.0.1:$head_port" --tiles-per-task 128 \
  --timings -q
ray_time=$(since "$t0")
same "$work/ray"
echo "R. pge-world, 2 tasks of 128 tiles: ${ray_time}s; variants and every tile equal L's"

rm -rf "$work/ray16"
t0=$(now)
pge-world "$script" --out "$work/ray16" --address "127.0.0.1:$head_port" -q
ray16_time=$(since "$t0")
same "$work/ray16"
echo "R16. pge-world, default batches (16 tasks of 16 tiles): ${ray16_time}s; equal to L's"

echo "ratios: R / L = $(echo "scale=2; $ray_time / $local_time" | bc)," \
  "R16 / L = $(echo "scale=2; $ray16_time / $local_time" | bc)"
echo "load after: $(uptime)"
