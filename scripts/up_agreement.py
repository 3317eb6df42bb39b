#!/usr/bin/env python3
"""One levelling path: do `--up -y` (the camera's axis given) and `--up auto`
(estimated) report the same doors on the same RGB-D frame?

Simulates frames (door_scene_sim --sensor rgbd, fixed seeds), runs
door_state_cli on each with both, and prints, per depth model, the frames
whose two up vectors agree within a degree and the share of those where both
report the same doors (as many, paired by opening centre within 0.3 m, equal
states, angles within 1 deg), with the frames that differ.

  scripts/up_agreement.py [--first-seed S] [--scenes N] [--models default,structured,tof,stereo]
                          [--robot-camera] [--jobs J]
"""
import argparse, json, math, os, subprocess, tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BIN = Path(os.environ["DSR_BIN"]) if os.environ.get("DSR_BIN") else Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin"


def report(pcd, up, out):
    subprocess.run([str(BIN / "door_state_cli"), "--quiet", "--up", up, "--json", out, pcd], check=True)
    with open(out) as f:
        return json.load(f)


def same_doors(a, b):
    da, db = a["doors"], b["doors"]
    if len(da) != len(db):
        return False
    left = list(db)
    for d in da:
        c = d["opening_center"]
        best = min(left, key=lambda e: math.dist(c, e["opening_center"]), default=None)
        if best is None or math.dist(c, best["opening_center"]) > 0.3:
            return False
        if best["state"] != d["state"] or abs(best["opening_angle_deg"] - d["opening_angle_deg"]) > 1.0:
            return False
        left.remove(best)
    return True


def one(args, model, seed, work):
    prefix = work / f"{model}_{seed}"
    sim = [str(BIN / "door_scene_sim"), "--quiet", "--sensor", "rgbd", "--seed", str(seed), "--out", str(prefix),
           "--formats", "pcd", "--depth-model", model] + (["--robot-camera"] if args.robot_camera else [])
    subprocess.run(sim, check=True)
    given = report(f"{prefix}.pcd", "-y", f"{prefix}.y.json")
    auto = report(f"{prefix}.pcd", "auto", f"{prefix}.auto.json")
    os.remove(f"{prefix}.pcd")
    cosang = sum(x * y for x, y in zip(given["up"], auto["up"]))
    angle = math.degrees(math.acos(max(-1.0, min(1.0, cosang))))
    return seed, angle, same_doors(given, auto), len(given["doors"]), len(auto["doors"])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--scenes", type=int, default=30)
    ap.add_argument("--models", default="default,structured,tof,stereo")
    ap.add_argument("--robot-camera", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="dsr_up_"))
    total_agree = total_n = 0
    for model in args.models.split(","):
        seeds = range(args.first_seed, args.first_seed + args.scenes)
        with ThreadPoolExecutor(args.jobs) as ex:
            rows = list(ex.map(lambda s: one(args, model, s, work), seeds))
        close = [r for r in rows if r[1] <= 1.0]
        agree = [r for r in close if r[2]]
        total_agree += len(agree)
        total_n += len(close)
        differ = " ".join(f"{s}({a:.2f}deg,{ny}/{na})" for s, a, ok, ny, na in close if not ok)
        far = " ".join(f"{s}({a:.1f}deg)" for s, a, *_ in rows if a > 1.0)
        print(f"{model}{'-robot' if args.robot_camera else ''}: up within 1 deg on {len(close)}/{len(rows)} frames; "
              f"same doors on {len(agree)}/{len(close)}" + (f"; differ: {differ}" if differ else "") +
              (f"; up apart: {far}" if far else ""), flush=True)
    print(f"all: same doors on {total_agree}/{total_n} frames whose up vectors agree within 1 deg")


if __name__ == "__main__":
    main()
