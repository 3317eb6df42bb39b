#!/usr/bin/env bash
# make latency: end-to-end latency of the door-state nodelet, from a
# PointCloud2 published (stamped at publish time) to the DoorStateArray that
# answers it, for simulated clouds played at a fixed rate from a rosbag.
#
#   scripts/nodelet_latency.sh [CASE ...]     (default: rgbd30 rgbddoor30 tls30 rgbd2 tls05 unload)
#
# Cases (clouds from door_scene_sim, seed 7 unless named, bags cached in $DSR_BUILD/latency):
#   rgbd30  one 640x480 RGB-D frame at 30 Hz (a camera's rate: overload);
#           seed 7's frame, no door in view
#   rgbddoor30  the RGB-D frame of seed 1001 at 30 Hz: a semi-open door in
#           view, the slowest of the bench's five door frames (the leaf
#           search runs on every cloud)
#   tls30   a 400k-ray laser scan at 30 Hz (overload)
#   rgbd2   the RGB-D frame at 2 Hz (no overload: latency of one cloud)
#   tls05   the laser scan at 0.5 Hz (no overload)
#   soak    both bags in turn at 10 Hz through tf (~fixed_frame map), for
#           SOAK_SECONDS (default 600): scripts/soak.sh
#   unload  the nodelet unloaded from its manager while clouds stream in at
#           30 Hz: the manager must survive (the destructor's clean shutdown)
#
# Each case starts its own nodelet manager with the nodelet loaded into it
# (config/default.yaml, up axis of the cloud), under a roscore of its own on
# a free port, runs build/bin/door_state_latency, and stops what it started,
# by PID. Seconds per case: LATENCY_SECONDS (default 30). Figures also go to
# $DSR_BUILD/latency/<case>.json.
# The manager runs with GOMP_SPINCOUNT=10000 (and glibc malloc's
# MALLOC_MMAP_THRESHOLD_ and MALLOC_TRIM_THRESHOLD_), as launch/door_state.launch
# starts it (argument omp_spincount), unless GOMP_SPINCOUNT or
# OMP_WAIT_POLICY is set in the environment: libgomp's default spin (300000,
# about 3 ms) takes the cores from the threads that receive and deserialize
# the clouds (laser 400k at 30 Hz: answers at 6.0 Hz and latency p50 341 ms
# with it, 8.4 Hz and 250 ms with 10000, one run each, 2026-11-25).
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
source "$REPO/scripts/nodelet_env.sh"
SECS="${LATENCY_SECONDS:-30}"
CASES=("$@")
[ ${#CASES[@]} -gt 0 ] || CASES=(rgbd30 rgbddoor30 tls30 rgbd2 tls05 unload)

for exe in door_scene_sim door_state_latency; do
  [ -x "$BIN/$exe" ] || { echo "nodelet_latency: $BIN/$exe missing: run make build first" >&2; exit 2; }
done

bag() {  # bag PREFIX SIM-ARGS...: simulate once, reuse afterwards
  local prefix="$1"; shift
  [ -s "$prefix.bag" ] || "$BIN/door_scene_sim" --quiet --formats bag,json --bag-count 1 --out "$prefix" "$@"
}
bag "$OUT/tls400k" --seed 7 --points 400000
bag "$OUT/rgbd" --sensor rgbd --seed 7
bag "$OUT/rgbd1001" --sensor rgbd --seed 1001

CORE="" MGR="" LOADER="" FAILED=0
cleanup() { stop "$LOADER"; stop "$MGR"; stop "$CORE"; }
trap cleanup EXIT

start_roscore "$OUT/roscore.log"

run() {  # run LABEL RATE SECONDS UP_AXIS FIXED_FRAME BAG...
  local label="$1" rate="$2" secs="$3" up="$4" fixed="$5"; shift 5
  local bags=() tf=()
  for b in "$@"; do bags+=(--bag "$b"); done
  [ -z "$fixed" ] || tf=(--tf)
  rosparam delete /door_state >/dev/null 2>&1 || true
  rosparam load "$REPO/config/default.yaml" /door_state
  rosparam set /door_state/up_axis "'$up'"  # quoted YAML: a leading '-' is no option
  [ -z "$fixed" ] || rosparam set /door_state/fixed_frame "$fixed"
  /usr/lib/nodelet/nodelet manager __name:=dsr_manager >"$OUT/$label.manager.log" 2>&1 &
  MGR=$!
  /usr/lib/nodelet/nodelet load door_state_recognition/DoorStateNodelet dsr_manager __name:=door_state \
    >"$OUT/$label.nodelet.log" 2>&1 &
  LOADER=$!
  "$BIN/door_state_latency" "${bags[@]}" "${tf[@]}" --rate "$rate" --seconds "$secs" --pid "$MGR" \
    --label "$label" --json "$OUT/$label.json" || { echo "nodelet_latency: case $label failed (logs in $OUT)" >&2; FAILED=1; }
  if kill -0 "$MGR" 2>/dev/null; then
    echo "  nodelet manager still running at the end: yes"
  else
    echo "nodelet_latency: the nodelet manager died during case $label (log: $OUT/$label.manager.log)" >&2
    FAILED=1
  fi
  # Unloading runs the nodelet's destructor in the manager, under load
  # (the worker may be in the middle of a cloud): the manager must survive it.
  local before=no
  for _ in $(seq 10); do publishes_doors && { before=yes; break; }; sleep 0.5; done
  stop "$LOADER"; LOADER=""
  for _ in $(seq 15); do publishes_doors || break; sleep 1; done
  if [ "$before" = yes ] && kill -0 "$MGR" 2>/dev/null && ! publishes_doors; then
    echo "  nodelet unloaded, manager still running: yes"
  else
    echo "nodelet_latency: unloading the nodelet failed or killed the manager (log: $OUT/$label.manager.log)" >&2
    FAILED=1
  fi
  stop "$MGR"; MGR=""
}

# Whether the nodelet (in dsr_manager) still advertises /doors.
publishes_doors() { rostopic info /doors 2>/dev/null | grep -q "/dsr_manager "; }

unload_under_load() {  # the nodelet unloaded while clouds stream in at 30 Hz and one is processed
  rosparam delete /door_state >/dev/null 2>&1 || true
  rosparam load "$REPO/config/default.yaml" /door_state
  /usr/lib/nodelet/nodelet manager __name:=dsr_manager >"$OUT/unload.manager.log" 2>&1 &
  MGR=$!
  /usr/lib/nodelet/nodelet load door_state_recognition/DoorStateNodelet dsr_manager __name:=door_state \
    >"$OUT/unload.nodelet.log" 2>&1 &
  LOADER=$!
  "$BIN/door_state_latency" --bag "$OUT/tls400k.bag" --rate 30 --seconds 12 --drain 2 --label unload \
    >"$OUT/unload.tool.log" 2>&1 &
  local tool=$!
  sleep 8
  local before=no
  for _ in $(seq 10); do publishes_doors && { before=yes; break; }; sleep 0.5; done
  stop "$LOADER"; LOADER=""
  for _ in $(seq 15); do publishes_doors || break; sleep 1; done
  if [ "$before" = yes ] && kill -0 "$MGR" 2>/dev/null && ! publishes_doors; then
    echo "unload: nodelet unloaded while clouds streamed in at 30 Hz, manager still running: yes"
  else
    echo "nodelet_latency: unloading under load failed or killed the manager (advertised before: $before; log: $OUT/unload.manager.log)" >&2
    rostopic info /doors >&2 || true
    FAILED=1
  fi
  wait "$tool" 2>/dev/null || true
  stop "$MGR"; MGR=""
}

echo "== nodelet latency, $(nproc) cores, cases: ${CASES[*]} (${SECS} s each, soak ${SOAK_SECONDS:-600} s); stamp at publish -> DoorStateArray received"
echo "   manager environment: GOMP_SPINCOUNT=${GOMP_SPINCOUNT:-unset} OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-unset} MALLOC_MMAP_THRESHOLD_=${MALLOC_MMAP_THRESHOLD_:-unset} MALLOC_TRIM_THRESHOLD_=${MALLOC_TRIM_THRESHOLD_:-unset}"
for c in "${CASES[@]}"; do
  case "$c" in
    rgbd30) run rgbd30 30 "$SECS" -y "" "$OUT/rgbd.bag" ;;
    rgbddoor30) run rgbddoor30 30 "$SECS" -y "" "$OUT/rgbd1001.bag" ;;
    tls30)  run tls30 30 "$SECS" +z "" "$OUT/tls400k.bag" ;;
    rgbd2)  run rgbd2 2 "$SECS" -y "" "$OUT/rgbd.bag" ;;
    tls05)  run tls05 0.5 "$SECS" +z "" "$OUT/tls400k.bag" ;;
    soak)   run "soak" 10 "${SOAK_SECONDS:-600}" +z map "$OUT/tls400k.bag" "$OUT/rgbd.bag" ;;
    unload) unload_under_load ;;
    *) echo "nodelet_latency: unknown case '$c' (rgbd30 rgbddoor30 tls30 rgbd2 tls05 soak unload)" >&2; exit 2 ;;
  esac
done
exit "$FAILED"
