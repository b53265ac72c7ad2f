#!/usr/bin/env bash
# The measurements of integrations/ray/README.md, in one run on one machine:
#   A. `pge run` of the whole forest (every core);
#   B. its tiles by `pge run --tile I,J --threads 1`, two at a time, without Ray;
#   B'. the same with a variant cache (--variant-cache, cold: a new folder);
#   C. the same tiles through pge-world on a local Ray cluster of two one-CPU nodes
#      (a head and one worker node on 127.0.0.1), with a cold variant cache, and
#   C'. again without the variant cache (--no-variant-cache), then (D) `pge merge`.
# Usage (from the repository root, after .ci/ray or with ray and pge-world installed):
#   integrations/ray/bench/measure.sh [SCRIPT] [WORKDIR]
set -euo pipefail
script=${1:-scripts/forests/big.lua}
work=${2:-$(mktemp -d /tmp/pgebench.XXXXXX)}
root=$(cd "$(dirname "$0")/../../.." && pwd)
venv=${VENV:-$root/target/ray-venv}
export PATH="$root/target/release:$venv/bin:$PATH" RAY_USAGE_STATS_ENABLED=0
mkdir -p "$work"
now() { date +%s.%N; }
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
echo "load before: $(uptime)"

t0=$(now)
pge run "$script" -o "$work/whole.glb" -q
t1=$(now)
whole=$(echo "$t1 - $t0" | bc)
echo "A. pge run, whole forest: ${whole}s, $(stat -c %s "$work/whole.glb") bytes"

mkdir -p "$work/local"
export SCRIPT=$script WORK=$work
t0=$(now)
pge tiles "$script" | grep -o '"i":[0-9]*,"j":[0-9]*' | sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/\1 \2/' |
  xargs -P 2 -L 1 sh -c 'pge run "$SCRIPT" --tile "$0,$1" --threads 1 -q -o "$WORK/local/$0_$1.glb"'
t1=$(now)
local_tiles=$(echo "$t1 - $t0" | bc)
echo "B. pge run --tile, 16 tiles two at a time: ${local_tiles}s, $(du -cb "$work"/local/*.glb | tail -1 | cut -f1) bytes"

mkdir -p "$work/cached"
t0=$(now)
pge tiles "$script" | grep -o '"i":[0-9]*,"j":[0-9]*' | sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/\1 \2/' |
  xargs -P 2 -L 1 sh -c 'pge run "$SCRIPT" --tile "$0,$1" --threads 1 -q -o "$WORK/cached/$0_$1.glb" --variant-cache "$WORK/variants-local"'
t1=$(now)
cached_tiles=$(echo "$t1 - $t0" | bc)
echo "B'. the same with a cold --variant-cache: ${cached_tiles}s, $(du -cb "$work"/variants-local | tail -1 | cut -f1) bytes of cache"
for f in "$work"/local/*.glb; do
  cmp -s "$f" "$work/cached/$(basename "$f")" || { echo "tile $(basename "$f") differs with the cache"; exit 1; }
done

temp=$(mktemp -d /tmp/pgerayb.XXXXXX)
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
t0=$(now)
pge-world "$script" --out "$work/world" --address "127.0.0.1:$head_port" \
  --variant-cache "$work/variants-ray"
t1=$(now)
ray_time=$(echo "$t1 - $t0" | bc)
echo "C. pge-world on Ray, 2 nodes x 1 CPU, cold variant cache: ${ray_time}s, $(du -cb "$work"/world/tiles/*.glb | tail -1 | cut -f1) bytes"
t0=$(now)
pge-world "$script" --out "$work/world-plain" --address "127.0.0.1:$head_port" --no-variant-cache
t1=$(now)
plain_time=$(echo "$t1 - $t0" | bc)
echo "C'. pge-world on Ray, 2 nodes x 1 CPU, no variant cache: ${plain_time}s"
for f in "$work"/local/*.glb; do
  cmp -s "$f" "$work/world/tiles/$(basename "$f")" || { echo "tile $(basename "$f") differs"; exit 1; }
  cmp -s "$f" "$work/world-plain/tiles/$(basename "$f")" || { echo "tile $(basename "$f") differs"; exit 1; }
done
echo "   every tile equals the local one"
t0=$(now)
pge merge "$work/world" -o "$work/merged.glb"
t1=$(now)
echo "D. pge merge: $(echo "$t1 - $t0" | bc)s, $(stat -c %s "$work/merged.glb") bytes"
echo "ratios: C / A = $(echo "scale=2; $ray_time / $whole" | bc)," \
  "C' / A = $(echo "scale=2; $plain_time / $whole" | bc)," \
  "B' / A = $(echo "scale=2; $cached_tiles / $whole" | bc)," \
  "B / A = $(echo "scale=2; $local_tiles / $whole" | bc)"
echo "load after: $(uptime)"
