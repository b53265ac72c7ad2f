#!/usr/bin/env bash
# An hour-long run of one fuzz target, as fuzz/README.md records them:
#   ./long-run.sh TARGET [libFuzzer options...]     (after cargo +nightly fuzz build -O)
# niced, in fork mode (a crash is recorded in artifacts/TARGET/ and the run goes on); its log,
# time (/usr/bin/time -v), a copy of the binary and the corpus counts go to runs/. New inputs
# go to corpus-work/TARGET; then minimise into the committed corpus with -merge=1 (README).
set -u
cd "$(dirname "$0")"
t=${1:?usage: ./long-run.sh TARGET [libFuzzer options...]}
shift
bin=$PWD/target/x86_64-unknown-linux-gnu/release/$t
mkdir -p runs "corpus-work/$t" "artifacts/$t"
cp "$bin" "runs/$t.bin"
echo "before $(find "corpus/$t" -type f | wc -l) start $(date -u +%FT%TZ)" >"runs/$t.meta"
nice -n 19 /usr/bin/time -v -o "runs/$t.time" "runs/$t.bin" -fork=1 -ignore_crashes=1 \
  -ignore_timeouts=1 -ignore_ooms=1 -max_total_time="${SECONDS_TOTAL:-3600}" -print_final_stats=1 \
  -timeout=30 -rss_limit_mb=2048 -len_control=0 "$@" -artifact_prefix="$PWD/artifacts/$t/" \
  "$PWD/corpus-work/$t" "$PWD/corpus/$t" >"runs/$t.log" 2>&1
status=$?
new=$(find "corpus-work/$t" -type f | wc -l)
echo "rc $status end $(date -u +%FT%TZ) new $new" >>"runs/$t.meta"
grep -E '^#[0-9]+: cov' "runs/$t.log" | tail -n 1
