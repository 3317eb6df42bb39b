#!/usr/bin/env bash
# make bench: our pipeline against the stock-PCL baseline (issue 5) on
# simulated scenes the bench generates itself with fixed seeds: laser rooms
# of 100k, 400k, 1M and 4M rays (400k also as two stations merged), one
# 64-beam LiDAR sweep, one 640x480 RGB-D frame and the first five RGB-D
# frames from seed 1000 on with a door in view, at 640x480 and 320x240. Per stage the
# median of BENCH_RUNS runs (default 5), peak memory of each implementation
# in a child process of its own, door accuracy of both against the truth, the
# ratio ours/stock and the cost against n log n. Prints the tables and writes
# $DSR_BUILD/bench/bench.json. Extra arguments go to door_state_bench
# (BENCH_ARGS="--skip-baseline-above 1000000", see door_state_bench --help).
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
OUT="$BUILD/bench"
mkdir -p "$OUT"
NOTE="commit $(git -C "$REPO" rev-parse --short HEAD 2>/dev/null || echo unknown)"
if [ -n "$(git -C "$REPO" status --porcelain --untracked-files=no -- src include 2>/dev/null)" ]; then
  NOTE="$NOTE + uncommitted changes in src/ or include/"
fi
# shellcheck disable=SC2086
"$BUILD/bin/door_state_bench" --runs "${BENCH_RUNS:-5}" --json "$OUT/bench.json" --note "$NOTE" ${BENCH_ARGS:-} "$@" \
  | tee "$OUT/bench.txt"
