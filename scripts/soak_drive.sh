#!/usr/bin/env bash
# make soak-drive: a simulated robot drive (door_scene_sim --drive) played in
# a loop through the door-state nodelet, as `bag_playback.launch loop:=true`
# plays it: use_sim_time, `rosbag play --clock --loop`, ~fixed_frame map, so
# that the fused tracks (tracked_doors) live through every loop and the
# clock goes back at each new one (the nodelet's rule: the tracks reset).
# For SOAK_SECONDS of wall time (default 1800) scripts/soak_drive_monitor.py
# records the nodelet manager's resident memory at every tenth, the messages
# received, the loops, the doors tracked and the last tracked_doors of each
# loop against the drive's truth. Exit 1 when the manager died or stopped
# publishing tracked_doors.
#
#   SOAK_SECONDS=1800 SOAK_SENSOR=lidar64 SOAK_SEED=3000 scripts/soak_drive.sh
#
# Figures in $DSR_BUILD/latency/soak_drive_<sensor>_<seed>.json, logs beside it.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
BIN="$BUILD/bin"
OUT="$BUILD/latency"
SECS="${SOAK_SECONDS:-1800}"
SENSOR="${SOAK_SENSOR:-lidar64}"
SEED="${SOAK_SEED:-3000}"
mkdir -p "$OUT"
export PATH=/usr/bin:$PATH
set +u; source "$BUILD/.ws/devel/setup.bash"; set -u
export ROS_LOG_DIR="$OUT/log"
# The manager's environment as door_state.launch sets it (see nodelet_latency.sh).
if [ -z "${GOMP_SPINCOUNT:-}" ] && [ -z "${OMP_WAIT_POLICY:-}" ]; then export GOMP_SPINCOUNT=10000; fi
if [ -z "${MALLOC_MMAP_THRESHOLD_:-}${MALLOC_TRIM_THRESHOLD_:-}${MALLOC_TOP_PAD_:-}${GLIBC_TUNABLES:-}" ]; then
  export MALLOC_MMAP_THRESHOLD_=67108864 MALLOC_TRIM_THRESHOLD_=1073741824
fi
PORT="${LATENCY_ROS_PORT:-$((20000 + RANDOM % 20000))}"
export ROS_MASTER_URI="http://localhost:$PORT"
[ -x "$BIN/door_scene_sim" ] || { echo "soak_drive: $BIN/door_scene_sim missing: run make build first" >&2; exit 2; }

PREFIX="$OUT/drive_${SENSOR}_${SEED}"
[ -s "$PREFIX.bag" ] && [ -s "$PREFIX.json" ] ||
  "$BIN/door_scene_sim" --drive --sensor "$SENSOR" --seed "$SEED" --formats bag,json --out "$PREFIX"

CORE="" MGR="" LOADER="" PLAYER=""
stop() {  # stop PID: SIGINT, then wait for it (only processes this script started)
  local pid="$1"
  [ -n "$pid" ] || return 0
  kill -INT "$pid" 2>/dev/null || true
  for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}
cleanup() { stop "$PLAYER"; stop "$LOADER"; stop "$MGR"; stop "$CORE"; }
trap cleanup EXIT

roscore -p "$PORT" >"$OUT/soak_drive.roscore.log" 2>&1 &
CORE=$!
for _ in $(seq 150); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
rosparam list >/dev/null 2>&1 || { echo "soak_drive: roscore on port $PORT did not come up" >&2; exit 1; }
rosparam set /use_sim_time true
rosparam load "$REPO/config/default.yaml" /door_state
rosparam set /door_state/fixed_frame map
/usr/lib/nodelet/nodelet manager __name:=dsr_manager >"$OUT/soak_drive.manager.log" 2>&1 &
MGR=$!
/usr/lib/nodelet/nodelet load door_state_recognition/DoorStateNodelet dsr_manager __name:=door_state \
  >"$OUT/soak_drive.nodelet.log" 2>&1 &
LOADER=$!
rosbag play --clock --loop -q -d 2 "$PREFIX.bag" >"$OUT/soak_drive.player.log" 2>&1 &
PLAYER=$!
echo "== soak-drive: $SENSOR drive of seed $SEED ($PREFIX.bag) in a loop through the nodelet for $SECS s"
STATUS=0
/usr/bin/python3 "$REPO/scripts/soak_drive_monitor.py" --seconds "$SECS" --pid "$MGR" --truth "$PREFIX.json" \
  --json "$OUT/soak_drive_${SENSOR}_${SEED}.json" || STATUS=1
if kill -0 "$MGR" 2>/dev/null; then
  echo "  nodelet manager still running at the end: yes"
else
  echo "soak_drive: the nodelet manager died (log: $OUT/soak_drive.manager.log)" >&2
  STATUS=1
fi
grep -c "reset" "$OUT/soak_drive.manager.log" | sed 's/^/  manager log lines naming a reset: /' || true
exit "$STATUS"
