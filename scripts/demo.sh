#!/usr/bin/env bash
# make demo: simulate a scene with known doors, show its ground truth, and -
# once the pipeline's command-line tool is built - run it and score it.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
BIN="$BUILD/bin"
OUT="$BUILD/demo"
SCENE="${DEMO_SCENE:-random}"
SEED="${DEMO_SEED:-4}"
mkdir -p "$OUT"
PREFIX="$OUT/scene"

echo "== simulating scene '$SCENE' (seed $SEED): laser scan of 400k rays, 5 mm range noise"
"$BIN/door_scene_sim" --scene "$SCENE" --seed "$SEED" --points 400000 --noise 0.005 \
  --formats pcd,ply,json,bag --out "$PREFIX"
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
    print(f"   decoy: {d['kind']} {d['height']:.2f} m tall")
PY

echo "== running the pipeline: door_state_cli $PREFIX.pcd"
"$BIN/door_state_cli" --json "$OUT/report.json" --reconstruction "$OUT/reconstruction.ply" "$PREFIX.pcd"
"$BIN/door_state_eval" "$PREFIX.json" "$OUT/report.json" > "$OUT/score.json"
echo "== doors found next to the truth (report: $OUT/report.json, walls rebuilt: $OUT/reconstruction.ply)"
/usr/bin/python3 - "$PREFIX.json" "$OUT/report.json" "$OUT/score.json" <<'PY'
import json, sys
t, r, s = (json.load(open(f)) for f in sys.argv[1:4])
by_truth = {m["truth_index"]: m for m in s["matches"]}
print(f"   {'truth':28s} {'found':28s} angle error  hinge error")
for i, d in enumerate(t["doors"]):
    truth = f"{d['state']} {d['opening_angle_deg']:.1f} deg"
    m = by_truth.get(i)
    if m:
        f = r["doors"][m["report_index"]]
        found = f"{f['state']} {f['opening_angle_deg']:.1f} deg"
        print(f"   door {i}: {truth:20s} {found:28s} {m['angle_error_deg']:6.2f} deg  {100*m['hinge_error_m']:6.1f} cm")
    else:
        print(f"   door {i}: {truth:20s} {'not found':28s}")
for j in s["unmatched_report"]:
    f = r["doors"][j]
    print(f"   (reported, matches no door: {f['state']} {f['opening_angle_deg']:.1f} deg)")
print(f"   precision {s['precision']:.2f}, recall {s['recall']:.2f}, state accuracy "
      f"{s['state_accuracy'] if s['state_accuracy'] is None else round(s['state_accuracy'], 2)}")
PY

echo "== the same scene as a rosbag, played through the nodelet (roslaunch bag_playback.launch rviz:=false)"
export PATH=/usr/bin:$PATH
set +u; source "$BUILD/.ws/devel/setup.bash"; set -u
PORT="${DEMO_ROS_PORT:-11366}"
export ROS_MASTER_URI="http://localhost:$PORT"
roslaunch -p "$PORT" door_state_recognition bag_playback.launch bag:="$PREFIX.bag" rviz:=false start_delay:=3 \
  > "$OUT/roslaunch.log" 2>&1 &
LAUNCH_PID=$!
trap 'kill -INT $LAUNCH_PID 2>/dev/null; sleep 2; kill -9 $LAUNCH_PID 2>/dev/null || true' EXIT
sleep 2
/usr/bin/python3 "$REPO/scripts/demo_listener.py" "$PREFIX.json" 2
echo "   (nodelet log: $OUT/roslaunch.log)"
