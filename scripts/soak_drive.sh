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
source "$REPO/scripts/nodelet_env.sh"
SECS="${SOAK_SECONDS:-1800}"
SENSOR="${SOAK_SENSOR:-lidar64}"
SEED="${SOAK_SEED:-3000}"
[ -x "$BIN/door_scene_sim" ] || { echo "soak_drive: $BIN/door_scene_sim missing: run make build first" >&2; exit 2; }

PREFIX="$OUT/drive_${SENSOR}_${SEED}"
[ -s "$PREFIX.bag" ] && [ -s "$PREFIX.json" ] ||
  "$BIN/door_scene_sim" --drive --sensor "$SENSOR" --seed "$SEED" --formats bag,json --out "$PREFIX"

CORE="" MGR="" LOADER="" PLAYER=""
cleanup() { stop "$PLAYER"; stop "$LOADER"; stop "$MGR"; stop "$CORE"; }
trap cleanup EXIT

start_roscore "$OUT/soak_drive.roscore.log"
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
