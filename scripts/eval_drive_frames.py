#!/usr/bin/env python3
"""Per-cloud accuracy on simulated drives: door_scene_sim --drive writes every
cloud of a drive with its truth in the sensor frame (--formats json,pcd);
door_state_cli runs on every EVERY-th cloud alone (no fusion), and
door_state_eval --in-view-only scores them all together ("in_view": the
sensor can see some of the doorway: LiDAR within its vertical field and
range, a camera in its image, with a clear sight line). Prints the merged
figures as JSON.

  scripts/eval_drive_frames.py [--sensor lidar16|lidar32|lidar64|lidar128|rgbd]
                               [--scenes N] [--first-seed S] [--every K] [--lidar-motion]
                               [--jobs J] [--out DIR]
"""
import argparse, glob, json, os, subprocess, tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BIN = Path(os.environ["DSR_BIN"]) if os.environ.get("DSR_BIN") else Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sensor", default="lidar64", choices=["lidar16", "lidar32", "lidar64", "lidar128", "rgbd"])
    ap.add_argument("--scenes", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--every", type=int, default=10, help="run the pipeline on every K-th cloud")
    ap.add_argument("--lidar-motion", action="store_true", help="door_scene_sim --lidar-motion (sweeps not deskewed)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="dsr_drive_frames_"))
    out.mkdir(parents=True, exist_ok=True)
    up = "-y" if args.sensor == "rgbd" else "+z"
    jobs = []
    for seed in range(args.first_seed, args.first_seed + args.scenes):
        prefix = out / f"{args.sensor}_{seed}"
        subprocess.run([str(BIN / "door_scene_sim"), "--quiet", "--drive", "--sensor", args.sensor, "--seed", str(seed),
                        "--formats", "json,pcd", "--out", str(prefix)] + (["--lidar-motion"] if args.lidar_motion else []),
                       check=True)
        frames = sorted(glob.glob(f"{prefix}.frame*.pcd"))
        for k, pcd in enumerate(frames):
            if k % args.every == 0:
                jobs.append(pcd[:-4])
            else:
                os.remove(pcd)

    def one(p):
        subprocess.run([str(BIN / "door_state_cli"), "--quiet", "--up", up, "--json", f"{p}.report.json", f"{p}.pcd"], check=True)
        return p

    with ThreadPoolExecutor(args.jobs) as ex:
        done = list(ex.map(one, jobs))
    pairs = out / "pairs.txt"
    pairs.write_text("".join(f"{p}.json {p}.report.json\n" for p in done))
    m = json.loads(subprocess.run([str(BIN / "door_state_eval"), "--in-view-only", "--pairs", str(pairs)], check=True,
                                  capture_output=True, text=True).stdout)
    summary = {k: m.get(k) for k in ["scenes", "true_doors", "reported_doors", "matched", "precision", "recall",
                                     "state_accuracy", "angle_mae_deg", "angle_lower_bounds", "hinge_error_median_m"]}
    summary.update(sensor=args.sensor, first_seed=args.first_seed, drives=args.scenes, every=args.every,
                   lidar_motion=args.lidar_motion)
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
