#!/usr/bin/env bash
# same_reports.sh OLD_BIN NEW_BIN [WORKDIR]: do two builds give the same
# doors? For changes meant to be exact (speed-ups): simulates a fixed set
# of inputs with OLD_BIN's door_scene_sim (camera frames of every depth
# family at 640x480 and 320x240, robot cameras, laser rooms, 64-beam
# sweeps), runs OLD_BIN's and NEW_BIN's door_state_cli --verbose on each
# (cameras with --up -y and --up auto), and compares the reports without
# their timing_ms and the verbose traces (every wall and doorway decision)
# without their timings. Prints the inputs that differ; exit 0 when none.
# OLD_BIN, NEW_BIN: folders holding door_scene_sim and door_state_cli
# (e.g. a copy of build/bin, with its libraries: LD_LIBRARY_PATH is set
# to the folder too). WORKDIR (default: a temporary folder) keeps
# the inputs and outputs.
set -euo pipefail
if [ $# -lt 2 ] || [ ! -x "$1/door_state_cli" ] || [ ! -x "$2/door_state_cli" ]; then
  echo "usage: same_reports.sh OLD_BIN NEW_BIN [WORKDIR] (folders holding door_scene_sim and door_state_cli)" >&2
  exit 2
fi
old=$(cd "$1" && pwd); new=$(cd "$2" && pwd)
work=${3:-$(mktemp -d)}
mkdir -p "$work/in" "$work/old" "$work/new"
sim() { LD_LIBRARY_PATH="$old" "$old/door_scene_sim" --quiet --formats pcd "$@" >/dev/null; }
in=$work/in
if [ ! -f "$in/.done" ]; then
  for s in $(seq 1000 1029); do sim --sensor rgbd --seed "$s" --out "$in/cam_$s"; done
  for s in $(seq 1000 1019); do sim --sensor rgbd --robot-camera --seed "$s" --out "$in/robot_$s"; done
  for s in $(seq 1000 1014); do sim --sensor rgbd --resolution 320x240 --seed "$s" --out "$in/qvga_$s"; done
  for s in $(seq 1000 1009); do sim --sensor rgbd --robot-camera --resolution 320x240 --seed "$s" --out "$in/rqvga_$s"; done
  for m in tof structured stereo; do
    for s in 1000 1001 1002; do sim --sensor rgbd --robot-camera --depth-model "$m" --seed "$s" --out "$in/${m}_$s"; done
  done
  for s in 1000 1001 1002 1003; do sim --seed "$s" --points 100000 --out "$in/laser_$s"; done
  for s in 1000 1001 1002; do sim --sensor lidar64 --seed "$s" --out "$in/lidar_$s"; done
  touch "$in/.done"
fi
run() {  # BIN OUT NAME ARGS...
  local bin=$1 out=$2 name=$3; shift 3
  LD_LIBRARY_PATH="$bin" "$bin/door_state_cli" "$@" --verbose --json "$out/$name.json" 2>"$out/$name.err" >/dev/null || true
  [ -f "$out/$name.json" ] && /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); d.pop('timing_ms', None)
json.dump(d, open(sys.argv[1], 'w'), indent=1, sort_keys=True)" "$out/$name.json"
  sed -i -E '/timings \(ms\)/d; s/ in [0-9.e+-]+ ms$//' "$out/$name.err"
}
differ=0 total=0
for f in "$in"/*.pcd; do
  n=$(basename "$f" .pcd)
  case $n in
    laser_*|lidar_*) variants=("$n:") ;;
    *) variants=("$n.y:--up -y" "$n.auto:--up auto") ;;
  esac
  for v in "${variants[@]}"; do
    name=${v%%:*}; args=${v#*:}
    # shellcheck disable=SC2086
    run "$old" "$work/old" "$name" $args "$f"
    # shellcheck disable=SC2086
    run "$new" "$work/new" "$name" $args "$f"
    total=$((total + 1))
    if ! cmp -s "$work/old/$name.json" "$work/new/$name.json" || ! cmp -s "$work/old/$name.err" "$work/new/$name.err"; then
      echo "differs: $name"
      differ=$((differ + 1))
    fi
  done
done
echo "$total runs, $differ differ (inputs and outputs in $work)"
[ "$differ" -eq 0 ]
