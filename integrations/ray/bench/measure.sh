#!/usr/bin/env bash
# The measurements of integrations/ray/README.md, in one run on one machine:
#   A. `pge run` of the whole forest (every core);
#   V. `pge run --variants-out` (every core): the shared variants, written once;
#   T. the tiles by `pge run --tile I,J --variants DIR --threads 1`, two at a time, no Ray;
#   B. the tiles in two batches, each ONE `pge run --tile I,J --tile ... --out-dir` (as
#      pge-world's tasks run them), two at a time, no Ray;
#   F. Ray's fixed cost: `ray.init` connecting to the cluster, then a first (empty) task (on
#      the driver's node, whose worker the first job finds prestarted); W: then an empty task
#      on the other node, whose worker starts on demand (as every worker of a later job);
#   C. pge-world on a local Ray cluster of two one-CPU nodes (a head and one worker node on
#      127.0.0.1), shared variants (the default), every file checked against V and T; its
#      phases (--timings);
#   S. pge-world --standalone-tiles with a cold variant cache (the former tile format);
#   D. `pge merge` of C's world.
# Usage (from the repository root, after .ci/ray or with ray and pge-world installed):
#   integrations/ray/bench/measure.sh [SCRIPT] [WORKDIR]
# STANDALONE=0 skips S.
set -euo pipefail
script=${1:-scripts/forests/big.lua}
work=${2:-$(mktemp -d /tmp/pgebench.XXXXXX)}
root=$(cd "$(dirname "$0")/../../.." && pwd)
venv=${VENV:-$root/target/ray-venv}
export PATH="$root/target/release:$venv/bin:$PATH" RAY_USAGE_STATS_ENABLED=0
mkdir -p "$work"
now() { date +%s.%N; }
since() { echo "$(now) - $1" | bc; }
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
whole=$(since "$t0")
echo "A. pge run, whole forest: ${whole}s, $(stat -c %s "$work/whole.glb") bytes"

mkdir -p "$work/local/tiles"
t0=$(now)
pge run "$script" --variants-out "$work/local" -q
variants=$(since "$t0")
echo "V. pge run --variants-out: ${variants}s, $(stat -c %s "$work/local/variants.bin") +" \
  "$(stat -c %s "$work/local/variants.json") bytes"
export SCRIPT=$script WORK=$work
t0=$(now)
pge tiles "$script" | grep -o '"i":[0-9]*,"j":[0-9]*' | sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/\1 \2/' |
  xargs -P 2 -L 1 sh -c 'pge run "$SCRIPT" --tile "$0,$1" --variants "$WORK/local" --threads 1 -q -o "$WORK/local/tiles/$0_$1.glb"'
local_tiles=$(since "$t0")
echo "T. pge run --tile --variants, 16 tiles two at a time: ${local_tiles}s," \
  "$(du -cb "$work"/local/tiles/*.glb | tail -1 | cut -f1) bytes"
mkdir -p "$work/local/batch"
pge tiles "$script" | grep -o '"i":[0-9]*,"j":[0-9]*' | sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/--tile \1,\2/' |
  awk '{ b[NR % 2] = b[NR % 2] " " $0 } END { print b[0]; print b[1] }' >"$work/batches"
t0=$(now)
# shellcheck disable=SC2016
xargs -P 2 -L 1 sh -c 'pge run "$SCRIPT" "$@" --variants "$WORK/local" --threads 1 -q --out-dir "$WORK/local/batch"' sh \
  <"$work/batches"
batched=$(since "$t0")
echo "B. two pge run --tile ... --out-dir of 8 tiles, two at a time: ${batched}s"
pge run "$script" --tile 1,1 --variants "$work/local" --threads 1 -q --stats -o "$work/one.glb" |
  sed 's/^/   tile 1,1: /'

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

# F: what any Ray job pays before its first task returns: Python and Ray imported, connected,
# a first task scheduled, its worker process started, its result back.
fixed=$("$venv/bin/python" - "127.0.0.1:$head_port" <<'EOF'
import sys, time
t0 = time.monotonic()
import ray
ray.init(address=sys.argv[1], _node_ip_address="127.0.0.1", logging_level="ERROR",
         log_to_driver=False)
t1 = time.monotonic()
ray.get(ray.remote(lambda: 1).options(num_cpus=1).remote())
t2 = time.monotonic()
# The first job on a cluster finds a worker prestarted on the driver's node; a worker on
# another node (and every worker of a later job, as pge-world's) starts on demand.
from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy
here = ray.get_runtime_context().get_node_id()
other = next(n["NodeID"] for n in ray.nodes() if n["Alive"] and n["NodeID"] != here)
ray.get(ray.remote(lambda: 1).options(
    num_cpus=1, scheduling_strategy=NodeAffinitySchedulingStrategy(other, soft=False)).remote())
t3 = time.monotonic()
print(f"{t1 - t0:.2f} {t2 - t1:.2f} {t2 - t0:.2f} {t3 - t2:.2f}")
EOF
)
read -r connect first fixed_total worker_start <<<"$fixed"
echo "F. Ray's fixed cost: import + connect ${connect}s, first task ${first}s, ${fixed_total}s in all;" \
  "W. a task on the other node (its worker started on demand): ${worker_start}s more"

t0=$(now)
pge-world "$script" --out "$work/world" --address "127.0.0.1:$head_port" --timings
ray_time=$(since "$t0")
echo "C. pge-world on Ray, 2 nodes x 1 CPU, shared variants: ${ray_time}s," \
  "$(du -cb "$work"/world/tiles/*.glb | tail -1 | cut -f1) bytes of tiles"
for f in variants.bin variants.json; do
  cmp -s "$work/local/$f" "$work/world/$f" || { echo "$f differs"; exit 1; }
done
for f in "$work"/local/tiles/*.glb; do
  cmp -s "$f" "$work/world/tiles/$(basename "$f")" || { echo "tile $(basename "$f") differs"; exit 1; }
done
for f in "$work"/local/batch/*.glb; do
  # The batch's files are in batch/, beside tiles/: the same URI, ../variants.bin.
  cmp -s "$f" "$work/local/tiles/$(basename "$f")" || { echo "batch $(basename "$f") differs"; exit 1; }
done
echo "   the variants and every tile equal the local ones"

if [ "${STANDALONE:-1}" != 0 ]; then
  t0=$(now)
  pge-world "$script" --out "$work/world-standalone" --address "127.0.0.1:$head_port" \
    --standalone-tiles --variant-cache "$work/variants-ray" -q
  standalone=$(since "$t0")
  echo "S. pge-world --standalone-tiles, cold variant cache: ${standalone}s," \
    "$(du -cb "$work"/world-standalone/tiles/*.glb | tail -1 | cut -f1) bytes"
fi

t0=$(now)
pge merge "$work/world" -o "$work/merged.glb"
echo "D. pge merge: $(since "$t0")s, $(stat -c %s "$work/merged.glb") bytes"
if [ "${STANDALONE:-1}" != 0 ]; then
  pge merge "$work/world-standalone" -o "$work/merged-standalone.glb"
  cmp -s "$work/merged.glb" "$work/merged-standalone.glb" || { echo "the merged worlds differ"; exit 1; }
  echo "   the same glb as the merged standalone tiles"
fi
echo "ratios: C / A = $(echo "scale=2; $ray_time / $whole" | bc)," \
  "(C - F) / A = $(echo "scale=2; ($ray_time - $fixed_total) / $whole" | bc)," \
  "(C - F - W) / A = $(echo "scale=2; ($ray_time - $fixed_total - $worker_start) / $whole" | bc)," \
  "T / A = $(echo "scale=2; $local_tiles / $whole" | bc)," \
  "B / A = $(echo "scale=2; $batched / $whole" | bc)," \
  "(V + T) / A = $(echo "scale=2; ($variants + $local_tiles) / $whole" | bc)"
[ -n "${standalone:-}" ] && echo "        S / A = $(echo "scale=2; $standalone / $whole" | bc)"
echo "load after: $(uptime)"
