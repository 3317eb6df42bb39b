#!/usr/bin/env bash
# make bench: times the simulator (median of repeated runs, measured here).
# The pipeline's benchmark joins this script when the pipeline lands.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BIN="$REPO/build/bin"
OUT="$REPO/build/bench"
RUNS="${BENCH_RUNS:-5}"
mkdir -p "$OUT"
median() { sort -n | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
now_ms() { date +%s%N | awk '{printf "%.1f", $1/1e6}'; }

echo "door_scene_sim, median of $RUNS runs on $(nproc) cores ($(uname -m)); times include writing the PCD"
printf "%-28s %10s %12s\n" case points median_ms
for spec in "tls 100000" "tls 400000" "tls 1000000" "tls 4000000" "rgbd 307200"; do
  set -- $spec
  times=()
  for r in $(seq "$RUNS"); do
    t0=$(now_ms)
    "$BIN/door_scene_sim" --quiet --sensor "$1" --points "$2" --seed "$r" --formats pcd --out "$OUT/bench_$1" 
    t1=$(now_ms)
    times+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN{print b-a}')")
  done
  printf "%-28s %10s %12s\n" "sim $1" "$2" "$(printf '%s\n' "${times[@]}" | median)"
done
