#!/usr/bin/env python3
"""make eval: the accuracy sweeps of the README's table, one line each.

Runs scripts/eval_sweep.py (30 scenes per sweep, fixed seeds) for every
sweep named below, or those given as arguments, and prints a Markdown table:
precision, recall, state accuracy (over every door found; over the measured
leaves alone), how many doors were reported not_closed (found, never a right
state), bound errors (a lower bound above the true angle), opening-angle mean
absolute error (with the error of measured angles alone and the number of lower
bounds), median hinge error, and of the true doors whose leaf the sensor saw
(half of it or more, the truth's leaf_in_view; laser scans and camera frames)
the share found in the right state. Each sweep's JSON and per-seed lines go to $DSR_BUILD/eval/NAME.json
and NAME.log (simulated clouds are deleted).

  scripts/eval_table.py [NAME ...]      (make eval; EVAL_SWEEPS="a b" selects)

Names: tls-400k-SEED, tls-100k-SEED, tls-1M-SEED, rgbd-SEED, lidar16-SEED,
lidar32-SEED, lidar64-SEED, lidar128-SEED (one sweep of a rotating LiDAR),
stations3-400k-SEED (three stations of 400k rays each), stations2-400k-SEED;
beyond-400k-SEED (one station inside and one beyond each door, 400k rays in
all); -nohandles- before the seed (leaves without handles, e.g.
rgbd-nohandles-SEED); -boundN- before the seed (tls-400k-bound90-SEED, stations3-400k-bound5-SEED)
runs with unseen_leaf_min_bound_deg N (the default is 5; 90 reports an unseen
leaf only when it is surely open, as before issue 20).
Registered clouds (issue 19; not in DEFAULT): merged2-400k-SEED and
merged3-400k-SEED (2 or 3 stations, 400k rays in all, merged into ONE cloud in
frame map with VIEWPOINT 0 0 0; the CLI gets that one file), mesh40k-SEED
(3 stations merged, then resampled as 40k mesh-like vertices), voxmap5cm-SEED
(3 stations merged, then the centres of occupied 5 cm voxels, as an
OctoMap or voxel SLAM map exports it). -clutter-,
-partition- or -corridor- before the seed give the random rooms those options
(e.g. merged3-400k-clutter-SEED, tls-400k-clutter-SEED); -varied- before
the seed varies the door joinery (door_scene_sim --varied-doors: a third of
rooms without casing); -ajar- before the seed opens the doors at random up
to 30 deg only (door_scene_sim --max-angle 30: leaves ajar, the least a
leaf shows of a doorway). EVAL_SCENES=N runs N
scenes per sweep instead of 30.
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
           [f"stations3-400k-bound90-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
           [f"stations3-100k-{s}" for s in (1000, 2000, 3000)] + ["stations3-1M-1000"] +
           [f"tls-400k-bound90-{s}" for s in (1000, 2000, 3000, 4000, 5000)] +
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
    elif parts[0] in ("merged2", "merged3"):  # stations merged into one cloud: the rays in total
        args = ["--sensor", "tls", "--viewpoints", parts[0][-1], "--merge", "--points", str(RAYS[parts[1]]),
                "--first-seed", seed]
    elif parts[0].startswith("voxmap"):  # voxmap5cm: 3 stations of 400k rays in all, merged, occupied 5 cm voxels
        args = ["--sensor", "tls", "--viewpoints", "3", "--points", "400000",
                "--voxel-map", str(int(parts[0][len("voxmap"):-2]) / 100), "--first-seed", seed]
    elif parts[0].startswith("mesh"):  # mesh40k: 3 stations of 400k rays in all, merged, 40k vertices
        args = ["--sensor", "tls", "--viewpoints", "3", "--points", "400000",
                "--mesh-like", str(int(parts[0][len("mesh"):-1]) * 1000), "--first-seed", seed]
    elif parts[0] in ("lidar16", "lidar32", "lidar64", "lidar128"):
        args = ["--sensor", parts[0], "--first-seed", seed]
    elif parts[0] == "beyond":  # one station inside, one beyond each door: the rays in total
        args = ["--sensor", "tls", "--beyond-doors", "--points", str(RAYS[parts[1]]), "--first-seed", seed]
    else:
        stations = 1 if parts[0] == "tls" else int(parts[0][len("stations"):])
        args = ["--sensor", "tls", "--viewpoints", str(stations), "--points", str(RAYS[parts[1]] * stations),
                "--first-seed", seed]
    args += [f"--{k}" for k in ("clutter", "partition", "corridor") if k in parts]
    args += ["--varied-doors"] if "varied" in parts else []
    args += ["--max-angle", "30"] if "ajar" in parts else []
    if os.environ.get("EVAL_SCENES"):
        args += ["--scenes", os.environ["EVAL_SCENES"]]
    if "nohandles" in parts:
        args += ["--no-handles"]
    for part in parts:
        if part.startswith("bound") and part[len("bound"):].isdigit():
            cfg = config_dir / f"{part}.yaml"
            cfg.write_text(f"unseen_leaf_min_bound_deg: {float(part[len('bound'):])}\n")
            args += ["--config", str(cfg)]
    return args


def seen(m):
    """The doors whose leaf was in sight (eval_sweep's leaf_seen): the share found in the right state."""
    s = m.get("leaf_seen")
    if not s or not s["true_doors"]:
        return "-"
    return f"{s['state_correct'] / s['true_doors']:.2f} ({s['state_correct']}/{s['true_doors']})"


def main():
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__.strip())
        return
    names = sys.argv[1:] or os.environ.get("EVAL_SWEEPS", "").split() or DEFAULT
    out = BUILD / "eval"
    out.mkdir(parents=True, exist_ok=True)
    print(f"| sweep ({os.environ.get('EVAL_SCENES', 30)} scenes) | P | R | state (measured) | not_closed | bound errors | "
          "angle MAE (measured; bounds) | median hinge | right, leaf seen |")
    print("|---|---|---|---|---|---|---|---|---|")
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
              f"{f(m['state_accuracy'], '%.2f')} ({f(m.get('state_accuracy_measured'), '%.2f')}) | "
              f"{m.get('not_closed') or 0} | {m.get('bound_errors') or 0} | {f(m['angle_mae_deg'], '%.1f')} deg "
              f"({f(m['angle_mae_measured_deg'], '%.1f')}; {m['angle_lower_bounds'] or 0}) | "
              f"{f(m['hinge_error_median_m'] and 100 * m['hinge_error_median_m'], '%.1f')} cm | {seen(m)} |", flush=True)


if __name__ == "__main__":
    main()
