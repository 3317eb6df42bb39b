#!/usr/bin/env python3
"""make eval: the accuracy sweeps of the README's table, one line each.

Runs scripts/eval_sweep.py (30 scenes per sweep, fixed seeds) for every
sweep named below, or those given as arguments, and prints a Markdown table:
precision, recall, state accuracy, opening-angle mean absolute error (with the
error of measured angles alone and the number of lower bounds), median hinge
error. Each sweep's JSON and per-seed lines go to $DSR_BUILD/eval/NAME.json
and NAME.log (simulated clouds are deleted).

  scripts/eval_table.py [NAME ...]      (make eval; EVAL_SWEEPS="a b" selects)

Names: tls-400k-SEED, tls-100k-SEED, tls-1M-SEED, rgbd-SEED,
stations3-400k-SEED (three stations of 400k rays each), stations2-400k-SEED;
beyond-400k-SEED (one station inside and one beyond each door, 400k rays in
all); -nohandles- before the seed (leaves without handles, e.g.
rgbd-nohandles-SEED); -bound5- before the seed (tls-400k-bound5-SEED, stations3-400k-bound5-SEED)
runs with unseen_leaf_min_bound_deg 5.
RGB-D camera families (not in the default list): rgbd-structured-SEED,
rgbd-tof-SEED, rgbd-stereo-SEED (door_scene_sim --depth-model), and
-robot- before the seed (rgbd-tof-robot-SEED, rgbd-robot-SEED: the camera's
pose as robots carry it, --robot-camera).
"""
import json, os, shutil, subprocess, sys, tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BUILD = Path(os.environ.get("DSR_BUILD", REPO / "build"))
DEFAULT = ([f"tls-400k-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"tls-100k-{s}" for s in (1000, 2000, 3000)] + ["tls-1M-1000"] +
           [f"rgbd-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"rgbd-nohandles-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"stations2-400k-{s}" for s in (1000, 2000, 3000, 4000)] +
           [f"stations3-400k-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"stations3-400k-bound5-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"stations3-100k-{s}" for s in (1000, 2000, 3000)] + ["stations3-1M-1000"] +
           [f"tls-400k-bound5-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"beyond-400k-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"beyond-100k-{s}" for s in (1000, 2000, 3000, 4000, 5000)] + ["beyond-1M-1000"])
RAYS = {"100k": 100000, "400k": 400000, "1M": 1000000}


def sweep_args(name, config_dir):
    parts = name.split("-")
    seed = parts[-1]
    if parts[0] == "rgbd":
        args = ["--sensor", "rgbd", "--first-seed", seed]
        args += next((["--depth-model", m] for m in ("structured", "tof", "stereo") if m in parts), [])
        args += ["--robot-camera"] if "robot" in parts else []
    elif parts[0] == "beyond":  # one station inside, one beyond each door: the rays in total
        args = ["--sensor", "tls", "--beyond-doors", "--points", str(RAYS[parts[1]]), "--first-seed", seed]
    else:
        stations = 1 if parts[0] == "tls" else int(parts[0][len("stations"):])
        args = ["--sensor", "tls", "--viewpoints", str(stations), "--points", str(RAYS[parts[1]] * stations),
                "--first-seed", seed]
    if "nohandles" in parts:
        args += ["--no-handles"]
    if "bound5" in parts:
        cfg = config_dir / "bound5.yaml"
        cfg.write_text("unseen_leaf_min_bound_deg: 5.0\n")
        args += ["--config", str(cfg)]
    return args


def main():
    names = sys.argv[1:] or os.environ.get("EVAL_SWEEPS", "").split() or DEFAULT
    out = BUILD / "eval"
    out.mkdir(parents=True, exist_ok=True)
    print("| sweep (30 scenes) | P | R | state | angle MAE (measured; bounds) | median hinge |")
    print("|---|---|---|---|---|---|")
    for name in names:
        work = Path(tempfile.mkdtemp(prefix=f"dsr_eval_{name}_"))
        try:
            args = sweep_args(name, work)
            with open(out / f"{name}.log", "w") as log:
                res = subprocess.run([sys.executable, str(REPO / "scripts" / "eval_sweep.py"), "--verbose",
                                      "--out", str(work)] + args, stdout=subprocess.PIPE, stderr=log, text=True,
                                     check=True)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        (out / f"{name}.json").write_text(res.stdout)
        m = json.loads(res.stdout)
        f = lambda v, fmt: "-" if v is None else fmt % v
        print(f"| {name} | {f(m['precision'], '%.2f')} | {f(m['recall'], '%.2f')} ({m['matched']}/{m['true_doors']}) | "
              f"{f(m['state_accuracy'], '%.2f')} | {f(m['angle_mae_deg'], '%.1f')} deg "
              f"({f(m['angle_mae_measured_deg'], '%.1f')}; {m['angle_lower_bounds'] or 0}) | "
              f"{f(m['hinge_error_median_m'] and 100 * m['hinge_error_median_m'], '%.1f')} cm |", flush=True)


if __name__ == "__main__":
    main()
