#!/usr/bin/env python3
"""Accuracy sweep: simulates scenes with fixed seeds, runs door_state_cli on
each, scores every report against its truth with door_state_eval, and prints
the merged figures as JSON (plus one line per scene with --verbose).

  scripts/eval_sweep.py [--sensor tls|rgbd|lidar16|lidar32|lidar64|lidar128] [--scenes N] [--first-seed S]
                        [--points N] [--viewpoints K] [--beyond-doors] [--no-handles] [--up AXIS] [--config FILE] [--jobs J]
                        [--merge] [--mesh-like N] [--voxel-map RES] [--clutter] [--partition] [--corridor]
                        [--varied-doors] [--max-angle DEG] [--frame-offset X,Y,Z]
                        [--depth-model M] [--robot-camera] [--verbose] [--out DIR]

With --merge or --mesh-like the CLI gets the one merged cloud (VIEWPOINT 0 0 0,
frame map), as a user holding a registered export would run it.
"""
import argparse, json, os, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
LEAF_SHARE = 0.5  # a leaf "seen": at least this share of it in sight (the truth's leaf_in_view)
BIN = Path(os.environ["DSR_BIN"]) if os.environ.get("DSR_BIN") else Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin"

def one(args, seed, out):
    prefix = out / f"{args.sensor}_{seed}"
    sim = [str(BIN / "door_scene_sim"), "--quiet", "--sensor", args.sensor, "--seed", str(seed),
           "--out", str(prefix), "--formats", "pcd,json"] + (["--no-handles"] if args.no_handles else [])
    sim += [f"--{k}" for k in ("clutter", "partition", "corridor") if getattr(args, k)]
    sim += ["--varied-doors"] if args.varied_doors else []
    sim += ["--max-angle", str(args.max_angle)] if args.max_angle is not None else []
    merged = args.merge or args.mesh_like > 0 or args.voxel_map > 0
    sim += ["--merge"] if args.merge else []
    sim += ["--frame-offset", args.frame_offset] if args.frame_offset else []
    sim += ["--mesh-like", str(args.mesh_like)] if args.mesh_like > 0 else []
    sim += ["--voxel-map", str(args.voxel_map)] if args.voxel_map > 0 else []
    if args.sensor == "rgbd":
        sim += ["--depth-model", args.depth_model] if args.depth_model else []
        sim += ["--robot-camera"] if args.robot_camera else []
    if args.sensor == "tls":
        sim += ["--points", str(args.points), "--noise", str(args.noise), "--viewpoints", str(args.viewpoints)]
        sim += ["--beyond-doors"] if args.beyond_doors else []
    subprocess.run(sim, check=True)
    up = args.up or ("-y" if args.sensor == "rgbd" else "+z")
    # Several scan positions: each station's own file (with its VIEWPOINT), as a survey delivers them.
    if args.sensor == "tls":
        with open(f"{prefix}.json") as f:
            stations = len(json.load(f)["sensor_origins"])
    else:
        stations = 1
    inputs = [f"{prefix}.station{k}.pcd" for k in range(stations)] if stations > 1 and not merged else [f"{prefix}.pcd"]
    config = ["--config", args.config] if args.config else []
    subprocess.run([str(BIN / "door_state_cli"), "--quiet", "--up", up, "--json", f"{prefix}.report.json"] + config + inputs,
                   check=True)
    res = subprocess.run([str(BIN / "door_state_eval"), "--in-view-only", f"{prefix}.json", f"{prefix}.report.json"],
                         check=True, capture_output=True, text=True)
    return seed, prefix, json.loads(res.stdout)

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sensor", default="tls", choices=["tls", "rgbd", "lidar16", "lidar32", "lidar64", "lidar128"])
    ap.add_argument("--scenes", type=int, default=30)
    ap.add_argument("--frame-offset", metavar="X,Y,Z", default="",
                    help="each cloud moved by this offset in its frame (door_scene_sim --frame-offset): "
                         "the same scans, the voxel grid cutting them elsewhere")
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--points", type=int, default=400000)
    ap.add_argument("--noise", type=float, default=0.005)
    ap.add_argument("--viewpoints", type=int, default=1,
                    help="TLS scan positions; above 1 the CLI gets each station's scan as its own file")
    ap.add_argument("--beyond-doors", action="store_true",
                    help="TLS: one more station in the room behind each door (door_scene_sim --beyond-doors)")
    ap.add_argument("--no-handles", action="store_true", help="leaves without handles (door_scene_sim --no-handles)")
    ap.add_argument("--merge", action="store_true",
                    help="TLS: the stations merged into one cloud in frame map (door_scene_sim --merge), one CLI input")
    ap.add_argument("--voxel-map", type=float, default=0, metavar="RES",
                    help="TLS: the merged cloud as occupied voxel centres of RES m (door_scene_sim --voxel-map RES)")
    ap.add_argument("--mesh-like", type=int, default=0, metavar="N",
                    help="TLS: the merged cloud resampled as N mesh vertices (door_scene_sim --mesh-like N)")
    ap.add_argument("--clutter", action="store_true", help="random rooms with clutter (door_scene_sim --clutter)")
    ap.add_argument("--partition", action="store_true", help="random rooms with a bathroom (door_scene_sim --partition)")
    ap.add_argument("--varied-doors", action="store_true",
                    help="door joinery varied per room, a third without casing (door_scene_sim --varied-doors)")
    ap.add_argument("--max-angle", type=float, default=None, metavar="DEG",
                    help="doors opened at random up to DEG (door_scene_sim --max-angle; default 130)")
    ap.add_argument("--corridor", action="store_true", help="corridors (door_scene_sim --corridor)")
    ap.add_argument("--depth-model", default=None, choices=["default", "structured", "tof", "stereo"],
                    help="RGB-D depth error of a camera family (door_scene_sim --depth-model)")
    ap.add_argument("--robot-camera", action="store_true", help="RGB-D pose as robots carry it (door_scene_sim --robot-camera)")
    ap.add_argument("--up", default=None)
    ap.add_argument("--config", default=None, help="parameters YAML passed to door_state_cli")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--verbose", action="store_true")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    if args.sensor != "tls" and (args.beyond_doors or args.viewpoints != 1 or args.merge or args.mesh_like or args.voxel_map):
        ap.error("--beyond-doors, --viewpoints, --merge, --mesh-like and --voxel-map are for --sensor tls")
    if args.sensor != "rgbd" and (args.depth_model or args.robot_camera):
        ap.error("--depth-model and --robot-camera are for --sensor rgbd")
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="dsr_sweep_"))
    out.mkdir(parents=True, exist_ok=True)
    seeds = range(args.first_seed, args.first_seed + args.scenes)
    with ThreadPoolExecutor(args.jobs) as ex:
        results = list(ex.map(lambda s: one(args, s, out), seeds))
    pairs = out / "pairs.txt"
    pairs.write_text("".join(f"{p}.json {p}.report.json\n" for _, p, _ in results))
    if args.verbose:
        for seed, prefix, r in results:
            truth = json.load(open(f"{prefix}.json"))
            # '-' after a door: less than half its leaf in sight of the sensor (its stations)
            desc = " ".join(f"{d['state'][:4]}{d['opening_angle_deg']:.0f}{'T' if d['swing']=='toward_viewer' else 'A'}"
                            f"{'-' if d.get('leaf_in_view', 1.0) < LEAF_SHARE else ''}"
                            for d in truth["doors"])
            # '>' a lower bound, 'NC' reported not_closed, 'B' a bound above the true angle, '!' state wrong
            errs = " ".join(f"{m['angle_error_deg']:.1f}{'>' if m.get('angle_is_lower_bound') else ''}"
                            f"/{m['hinge_error_m']:.2f}{'NC' if m.get('not_closed') else ''}"
                            f"{'B' if m.get('bound_error') else ''}{'' if m['state_correct'] else '!'}"
                            for m in r["matches"])
            print(f"seed {seed}: truth [{desc}] matched {r['matched']}/{r['true_doors']} reported {r['reported_doors']}"
                  f" errs(deg/m) {errs} missed {r['missed_truth']} extra {r['unmatched_report']}", file=sys.stderr)
    merged = subprocess.run([str(BIN / "door_state_eval"), "--in-view-only", "--pairs", str(pairs)], check=True,
                            capture_output=True, text=True)
    m = json.loads(merged.stdout)
    summary = {k: m.get(k) for k in ["scenes", "true_doors", "reported_doors", "matched", "precision", "recall",
                                     "state_accuracy", "state_accuracy_measured", "not_closed", "bound_errors",
                                     "angle_mae_deg", "angle_mae_measured_deg",
                                     "angle_lower_bounds", "hinge_error_median_m"]}
    # The doors whose leaf the sensor saw (at least LEAF_SHARE of it; truth of
    # RGB-D frames and laser scans): how many of them were found in the right
    # state. A leaf out of sight can at best be reported not_closed.
    if all("leaf_in_view" in d for _, p, _ in results for d in json.load(open(f"{p}.json"))["doors"]):
        seen = json.loads(subprocess.run([str(BIN / "door_state_eval"), "--leaf-in-view-only", str(LEAF_SHARE),
                                          "--pairs", str(pairs)], check=True, capture_output=True, text=True).stdout)
        summary["leaf_seen"] = {"share": LEAF_SHARE, "true_doors": seen["true_doors"],
                                "state_correct": seen["state_correct"], "precision": seen["precision"],
                                "angle_mae_measured_deg": seen["angle_mae_measured_deg"]}
    summary.update(sensor=args.sensor, first_seed=args.first_seed)
    if args.sensor == "rgbd":
        summary.update(depth_model=args.depth_model or "default", robot_camera=args.robot_camera)
    if args.sensor == "tls":
        summary.update(points=args.points, viewpoints=args.viewpoints, beyond_doors=args.beyond_doors,
                       merge=args.merge, mesh_like=args.mesh_like, voxel_map=args.voxel_map)
    summary.update({k: True for k in ("clutter", "partition", "corridor", "varied_doors") if getattr(args, k)})
    summary.update({"max_angle": args.max_angle} if args.max_angle is not None else {})
    print(json.dumps(summary, indent=1))

if __name__ == "__main__":
    main()
