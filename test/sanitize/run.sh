#!/usr/bin/env bash
# Builds the core, the simulator and their gtest tests with AddressSanitizer +
# UndefinedBehaviorSanitizer (test/sanitize/CMakeLists.txt) and runs them.
# Exits non-zero when the build fails, a test fails, or a sanitizer reports
# anything (every report is fatal). Usage: run.sh BUILD_DIR [JOBS]
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
OUT="${1:?usage: run.sh BUILD_DIR [JOBS]}"
JOBS="${2:-2}"
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
start=$(date +%s)

echo "sanitize: building (ASan+UBSan, gcc, -O2) in $OUT, log $OUT/build.log"
if ! { cmake -S "$HERE" -B "$OUT" -DCMAKE_BUILD_TYPE=Sanitize >"$OUT/build.log" 2>&1 &&
       cmake --build "$OUT" -j"$JOBS" >>"$OUT/build.log" 2>&1; }; then
  tail -n 40 "$OUT/build.log"; echo "sanitize: build failed (full log: $OUT/build.log)"; exit 1
fi
built=$(date +%s)
echo "sanitize: built in $((built - start)) s"

# halt_on_error: the first report ends the test with a non-zero exit.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1:strict_string_checks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$HERE/ubsan.supp"
export LSAN_OPTIONS="suppressions=$HERE/lsan.supp:print_suppressions=0"
# Two threads: the machine is shared and OpenMP would otherwise take every core.
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"

failed=()
# The canary must be caught by both sanitizers, else the flags are not in effect.
if "$OUT/canary" asan >"$OUT/canary.log" 2>&1 || ! grep -q "heap-buffer-overflow" "$OUT/canary.log"; then
  echo "sanitize: ASan did not catch the canary's overflow"; failed+=(canary-asan)
fi
if "$OUT/canary" ubsan >"$OUT/canary.log" 2>&1 || ! grep -q "runtime error: signed integer overflow" "$OUT/canary.log"; then
  echo "sanitize: UBSan did not catch the canary's overflow"; failed+=(canary-ubsan)
fi
if "$OUT/canary" floatcast >"$OUT/canary.log" 2>&1 || ! grep -q "runtime error: .* is outside the range of representable values" "$OUT/canary.log"; then
  echo "sanitize: UBSan did not catch the canary's float-to-int overflow"; failed+=(canary-floatcast)
fi
for t in test_cloud_reader test_cloud_conversion test_evaluation test_neighbours test_simulator test_pipeline test_sight test_fusion; do
  exe="$OUT/$t"
  [ -x "$exe" ] || { echo "sanitize: $t was not built"; failed+=("$t"); continue; }
  t0=$(date +%s)
  if "$exe" --gtest_brief=1 >"$OUT/$t.log" 2>&1; then
    tests=$(grep -oE '^\[==========\] [0-9]+ tests' "$OUT/$t.log" | grep -oE '[0-9]+' | tail -n 1)
    echo "sanitize: $t passed (${tests:-?} tests, $(( $(date +%s) - t0 )) s)"
  else
    echo "sanitize: $t FAILED, last lines of $OUT/$t.log:"
    grep -E "ERROR: |runtime error|SUMMARY|FAILED|Failure" "$OUT/$t.log" | head -n 20 || tail -n 30 "$OUT/$t.log"
    failed+=("$t")
  fi
done
echo "sanitize: build $((built - start)) s, tests $(( $(date +%s) - built )) s"
if [ ${#failed[@]} -gt 0 ]; then echo "sanitize: FAILED: ${failed[*]}"; exit 1; fi
echo "sanitize: all clean (canary caught by ASan and UBSan)"
