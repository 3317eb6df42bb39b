#!/usr/bin/env bash
# make demo: simulate a room with a closed, a semi-open and an open door, find
# them from the file (door_state_cli) and through the nodelet (a rosbag played
# by bag_playback.launch), print each against the truth with a line saying
# why for any door missed or reported as a bound, and write a plan (SVG).
# Then a robot's drive (door_scene_sim --drive) played through
# door_state.launch: the last tracked_doors against the truth.
#
# The scene: a random room of DEMO_SEED with three doors (--doors 3:3). The
# seed was picked, among the first seeds of that kind, as one where the three
# doors are in the three states and all three are found from a single scan;
# on other seeds a door whose leaf is out of the scanner's sight is missed, and
# the demo says so (DEMO_SEED=N make demo shows another room).
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
BIN="$BUILD/bin"
OUT="$BUILD/demo"
SCENE="${DEMO_SCENE:-random}"
SEED="${DEMO_SEED:-14}"
mkdir -p "$OUT"
PREFIX="$OUT/scene"
DOORS=()
[ "$SCENE" = random ] && DOORS=(--doors "${DEMO_DOORS:-3:3}")

echo "== simulating scene '$SCENE' (seed $SEED): one laser scan of 400k rays, 5 mm range noise"
"$BIN/door_scene_sim" --quiet --scene "$SCENE" --seed "$SEED" "${DOORS[@]}" --points 400000 --noise 0.005 \
  --formats pcd,ply,json,bag --bag-count 10 --out "$PREFIX"   # 10 clouds at 1 Hz: the listener takes the first 2 it hears
echo "   wrote $PREFIX.pcd, .ply, .bag and the ground truth $PREFIX.json"

echo "== ground truth (cloud frame, metres, degrees)"
/usr/bin/python3 - "$PREFIX.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
print(f"   sensor {t['sensor']}, frame {t['frame_id']}, floor {t['floor']:.2f} m, ceiling {t['ceiling']:.2f} m")
for i, d in enumerate(t["doors"]):
    c = d["opening_center"]
    print(f"   door {i}: {d['state']:9s} {d['opening_angle_deg']:6.1f} deg  width {d['width']:.2f} m  "
          f"hinge {d['hinge_side']:5s} swings {d['swing']:16s} centre ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f})")
for d in t["decoys"]:
    print(f"   look-alike: {d['kind']} {d['height']:.2f} m tall")
PY

echo "== the file: door_state_cli --json --svg --reconstruction $PREFIX.pcd"
"$BIN/door_state_cli" --quiet --json "$OUT/report.json" --svg "$OUT/plan.svg" \
  --reconstruction "$OUT/reconstruction.ply" "$PREFIX.pcd"
"$BIN/door_state_eval" "$PREFIX.json" "$OUT/report.json" > "$OUT/score.json"
echo "== doors found next to the truth"
/usr/bin/python3 "$REPO/scripts/demo_table.py" "$PREFIX.json" "$OUT/report.json" "$OUT/score.json" "$PREFIX.pcd"
echo "   report: $OUT/report.json; walls rebuilt: $OUT/reconstruction.ply"
echo "   plan (top view, open it in a browser): $OUT/plan.svg"

echo "== the same scene as a rosbag, played through the nodelet (roslaunch bag_playback.launch rviz:=false)"
export PATH=/usr/bin:$PATH
set +u; source "$BUILD/.ws/devel/setup.bash"; set -u
PORT="${DEMO_ROS_PORT:-11366}"
export ROS_MASTER_URI="http://localhost:$PORT"
roslaunch -p "$PORT" door_state_recognition bag_playback.launch bag:="$PREFIX.bag" rviz:=false start_delay:=3 \
  > "$OUT/roslaunch.log" 2>&1 &
LAUNCH_PID=$!
trap 'kill -INT $LAUNCH_PID 2>/dev/null; sleep 2; kill -9 $LAUNCH_PID 2>/dev/null || true' EXIT
for _ in $(seq 1 60); do rosnode list >/dev/null 2>&1 && break; sleep 0.5; done   # the master is up
/usr/bin/python3 "$REPO/scripts/demo_listener.py" "$PREFIX.json" 2
echo "   (a door not found here is missed for the reason given above: the nodelet runs the same pipeline)"
echo "   (nodelet log: $OUT/roslaunch.log)"
kill -INT $LAUNCH_PID 2>/dev/null; wait $LAUNCH_PID 2>/dev/null || true
trap - EXIT

if [ "${DEMO_DRIVE:-1}" != 0 ]; then
  DRIVE_SEED="${DEMO_DRIVE_SEED:-14}"
  echo "== a robot's drive (seed $DRIVE_SEED): a 64-beam LiDAR on a mast passes three doors, 4 sweeps/s (door_scene_sim --drive)"
  "$BIN/door_scene_sim" --quiet --drive --sensor lidar64 --seed "$DRIVE_SEED" --doors 3:3 --rate 4 --out "$OUT/drive"
  echo "   wrote $OUT/drive.bag (/points in the sensor frame, /tf map -> base_link -> sensor, /clock) and the truth $OUT/drive.json (in map)"
  echo "== the bag played through door_state.launch fixed_frame:=map (use_sim_time; the bag brings its own /clock)"
  DRIVE_PORT=$((PORT + 1))
  export ROS_MASTER_URI="http://localhost:$DRIVE_PORT"
  roscore -p "$DRIVE_PORT" > "$OUT/drive_roscore.log" 2>&1 &
  CORE_PID=$!
  trap 'kill -INT $DRIVE_LAUNCH_PID 2>/dev/null; sleep 2; kill $CORE_PID 2>/dev/null || true' EXIT
  DRIVE_LAUNCH_PID=
  for _ in $(seq 1 60); do rosparam list >/dev/null 2>&1 && break; sleep 0.5; done
  rosparam set /use_sim_time true
  roslaunch door_state_recognition door_state.launch points:=/points fixed_frame:=map > "$OUT/drive_roslaunch.log" 2>&1 &
  DRIVE_LAUNCH_PID=$!
  sleep 4   # the nodelet up and subscribed
  /usr/bin/python3 "$REPO/scripts/demo_drive_listener.py" "$OUT/drive.json" 8 &
  LISTENER_PID=$!
  rosbag play -q "$OUT/drive.bag" > "$OUT/drive_play.log" 2>&1
  wait $LISTENER_PID || true
  echo "   (doors seen in a few clouds that are not there are the drive's known failure: doc/results.md, Drives)"
  echo "   (nodelet log: $OUT/drive_roslaunch.log; the bag, $(du -h "$OUT/drive.bag" | cut -f1), is deleted: DEMO_DRIVE=0 skips this part)"
  rm -f "$OUT/drive.bag"
fi
echo "== plan of the scene: $OUT/plan.svg"
