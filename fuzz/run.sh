#!/usr/bin/env bash
# Builds the libFuzzer targets with Debian's clang 14 (fuzz/CMakeLists.txt)
# and runs each for SECONDS, starting from the seed corpus in fuzz/corpus/.
# New inputs go to BUILD_DIR/corpus/<target> (the repo's corpus stays as
# committed); a crash leaves its input in BUILD_DIR/artifacts/<target>/.
# Prints runs, seconds and the result of each target; exits non-zero when a
# target crashed, leaked, timed out or ran out of memory.
#   usage: run.sh BUILD_DIR [SECONDS] [TARGET...]      (make fuzz FUZZ_SECONDS=60)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
OUT="${1:?usage: run.sh BUILD_DIR [SECONDS] [TARGET...]}"
SECONDS_EACH="${2:-60}"
shift $(( $# >= 2 ? 2 : 1 ))
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(fuzz_cloud_reader fuzz_pointcloud2 fuzz_pipeline)
JOBS="${JOBS:-2}"
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

echo "fuzz: building with clang++-14 in $OUT (log $OUT/build.log)"
if ! { cmake -S "$HERE" -B "$OUT" >"$OUT/build.log" 2>&1 && cmake --build "$OUT" -j"$JOBS" >>"$OUT/build.log" 2>&1; }; then
  tail -n 40 "$OUT/build.log"; echo "fuzz: build failed (full log: $OUT/build.log)"; exit 1
fi

# Per target: longest input (bytes) and the time one input may take (s).
declare -A MAX_LEN=([fuzz_cloud_reader]=8192 [fuzz_pointcloud2]=2048 [fuzz_pipeline]=40000)
declare -A TIMEOUT=([fuzz_cloud_reader]=10 [fuzz_pointcloud2]=10 [fuzz_pipeline]=60)
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1:strict_string_checks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"

status=0
summary=()
for t in "${TARGETS[@]}"; do
  work="$OUT/corpus/$t"; art="$OUT/artifacts/$t/"
  mkdir -p "$work" "$art"
  log="$OUT/$t.log"
  echo "fuzz: $t for ${SECONDS_EACH} s (log $log)"
  t0=$(date +%s)
  set +e
  "$OUT/$t" -max_total_time="$SECONDS_EACH" -max_len="${MAX_LEN[$t]}" -timeout="${TIMEOUT[$t]}" \
    -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$art" \
    "$work" "$HERE/corpus/$t" >"$log" 2>&1
  rc=$?
  set -e
  # (|| true: a crashed run prints no "Done" line, and pipefail must not end the script)
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -n 1 || true)
  secs=$(grep -oE 'Done [0-9]+ runs in [0-9]+ second' "$log" | grep -oE 'in [0-9]+' | grep -oE '[0-9]+' | tail -n 1 || true)
  [ -n "$secs" ] || secs="$(( $(date +%s) - t0 )) (crashed)"
  cov=$(grep -oE '^#[0-9]+.*cov: [0-9]+' "$log" | tail -n 1 | grep -oE 'cov: [0-9]+' || true)
  if [ $rc -eq 0 ]; then
    result="clean"
  else
    status=1
    result="FAILED (exit $rc): $(grep -m1 -oE 'ERROR: [A-Za-z]+: .*|runtime error: .*|deadly signal|Test unit written to .*' "$log" | head -n 1 || true)"
    grep -E 'Test unit written to' "$log" | tail -n 1 || true
  fi
  line="$t: ${runs:-?} runs in ${secs} s, ${cov:-cov: ?}, corpus $(ls "$work" | wc -l) + $(ls "$HERE/corpus/$t" | wc -l) seeds: $result"
  echo "fuzz: $line"
  summary+=("$line")
done
echo "fuzz: summary (${SECONDS_EACH} s each)"
printf '  %s\n' "${summary[@]}"
exit $status
