#!/usr/bin/env python3
"""Camera figures scored three ways (issue 21), one Markdown row per sweep.

Reads folders written by `eval_sweep.py --sensor rgbd --out DIR` (PREFIX.json
truth, PREFIX.report.json per frame, pairs.txt) and scores every frame with
door_state_eval three ways:

  centre  the truth doors whose doorway's middle, 1 m above the floor,
          projects into the image within range (the camera truth's "in_view"
          before issue 21, recomputed here: no occlusion test)
  in view door_state_eval --in-view-only (a clear sight line to the doorway)
  leaf    door_state_eval --leaf-in-view-only SHARE (default 0.5): the doors
          whose leaf the camera sees, at least SHARE of it

and prints per sweep and way: truth doors scored, P, R, the share of them
found in the right state ("right"), state accuracy over the doors found and
over the measured leaves, and the angle MAE over measured leaves.

  scripts/camera_view_table.py DIR [DIR ...] [--share S] [--bin BUILD_BIN] [--json OUT.json]

A folder's depth family sets the range of the centre test (tof 10 m, stereo
8 m, else 4.5 m): taken from its name (rgbd-tof-..., rgbd-stereo-...) unless
--max-range is given. Images are 640 x 480 (eval_sweep's frames).
"""
import argparse, json, os, subprocess, sys, tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def centre_in_view(door, up, max_range, width=640, height=480, f=525.0):
    """The old camera test: the doorway's middle 1 m up inside the image, within range."""
    p = [door["opening_center"][i] + up[i] for i in range(3)]
    if p[2] < 0.5 or p[2] > max_range:
        return False
    u = f * p[0] / p[2] + (width - 1) / 2.0
    v = f * p[1] / p[2] + (height - 1) / 2.0
    return 0 <= u < width and 0 <= v < height


def score(bin_dir, pairs, options):
    out = subprocess.run([str(Path(bin_dir) / "door_state_eval")] + options + ["--pairs", str(pairs)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def figures(m):
    n = m["true_doors"]
    return {"doors": n, "reported": m["reported_doors"], "matched": m["matched"], "right": m["state_correct"],
            "P": m["precision"], "R": m["recall"], "right_share": m["state_correct"] / n if n else None,
            "state_acc": m["state_accuracy"], "state_acc_measured": m["state_accuracy_measured"],
            "mae_measured": m["angle_mae_measured_deg"], "lower_bounds": m["angle_lower_bounds"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--share", type=float, default=0.5)
    ap.add_argument("--max-range", type=float, default=None)
    ap.add_argument("--bin", default=os.environ.get("DSR_BIN", str(Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin")))
    ap.add_argument("--json", default=None, help="write every figure there too")
    args = ap.parse_args()
    f = lambda v, fmt: "-" if v is None else fmt % v
    print("| sweep | scored | doors | P | R | right | state (measured) | angle MAE measured |")
    print("|---|---|---|---|---|---|---|---|")
    every = {}
    for d in args.dirs:
        d = Path(d)
        name = d.name
        max_range = args.max_range or (10.0 if "-tof-" in name else 8.0 if "-stereo-" in name else 4.5)
        pairs = d / "pairs.txt"
        rows = {}
        with tempfile.TemporaryDirectory(prefix="dsr_centre_") as tmp:
            lines = []
            for line in pairs.read_text().splitlines():
                gt, rep = line.split()
                truth = json.loads(Path(gt).read_text())
                for door in truth["doors"]:
                    door["in_view"] = centre_in_view(door, truth["up"], max_range)
                copy = Path(tmp) / Path(gt).name
                copy.write_text(json.dumps(truth))
                lines.append(f"{copy} {rep}\n")
            (Path(tmp) / "pairs.txt").write_text("".join(lines))
            rows["centre"] = figures(score(args.bin, Path(tmp) / "pairs.txt", ["--in-view-only"]))
        rows["in view"] = figures(score(args.bin, pairs, ["--in-view-only"]))
        rows[f"leaf >= {args.share:g}"] = figures(score(args.bin, pairs, ["--leaf-in-view-only", str(args.share)]))
        every[name] = rows
        for way, r in rows.items():
            print(f"| {name} | {way} | {r['doors']} | {f(r['P'], '%.2f')} | {f(r['R'], '%.2f')} ({r['matched']}) | "
                  f"{f(r['right_share'], '%.2f')} ({r['right']}) | {f(r['state_acc'], '%.2f')} "
                  f"({f(r['state_acc_measured'], '%.2f')}) | {f(r['mae_measured'], '%.1f')} deg |", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(every, indent=1) + "\n")


if __name__ == "__main__":
    main()
