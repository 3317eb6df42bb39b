#!/usr/bin/env bash
# Renders rviz headless (Xvfb, Mesa software GL) on a simulated scene played
# through the nodelet, and saves a screenshot.
#   scripts/rviz_shot.sh [OUT.png] [SEED]      (make rviz-shot)
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
OUT="${1:-$REPO/doc/rviz_door_state.png}"
SEED="${2:-4}"
WORK="$BUILD/rviz_shot"
DISPLAY_NUM="${RVIZ_SHOT_DISPLAY:-77}"
PORT="${RVIZ_SHOT_PORT:-11377}"
mkdir -p "$WORK" "$(dirname "$OUT")"
export PATH=/usr/bin:$PATH
set +u; source "$BUILD/.ws/devel/setup.bash"; set -u
export ROS_MASTER_URI="http://localhost:$PORT"

"$BUILD/bin/door_scene_sim" --quiet --seed "$SEED" --points 400000 --formats bag,json \
  --bag-count 40 --bag-rate 1 --out "$WORK/scene"

pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done; sleep 2;
            for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
Xvfb ":$DISPLAY_NUM" -screen 0 1280x800x24 >"$WORK/xvfb.log" 2>&1 &
pids+=($!)
sleep 2
DISPLAY=":$DISPLAY_NUM" roslaunch -p "$PORT" door_state_recognition bag_playback.launch bag:="$WORK/scene.bag" \
  rviz:=true loop:=true >"$WORK/roslaunch.log" 2>&1 &
pids+=($!)
echo "rviz_shot: waiting for rviz to draw the doors..."
sleep "${RVIZ_SHOT_WAIT:-25}"
DISPLAY=":$DISPLAY_NUM" import -window root "$OUT"
echo "rviz_shot: wrote $OUT"
