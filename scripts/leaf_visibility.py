#!/usr/bin/env python3
"""How much of each missed door's leaf did the scan see?

Reads a folder written by `eval_sweep.py --out DIR` (PREFIX.pcd, PREFIX.json
truth, PREFIX.report.json per scene; a laser scan, or an RGB-D frame in its
camera frame, heights taken along the truth's "up"), scores each scene with
door_state_eval, and for every truth door in view that no reported door
matched prints the share of its leaf's 5 cm x 10 cm cells (over the body of
the leaf, 0.25-1.75 m above the floor, as the leaf search uses) that hold at
least one point of the scan within 6 cm of the leaf's true plane, and the
share of them more than 10 cm from the hinge (what a jamb or trim at the
hinge cannot put there). A share near 0 means the scan position did not see
the leaf at all.

  scripts/leaf_visibility.py DIR [--bin BUILD_BIN]
"""
import argparse, json, math, os, subprocess, sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent


def read_pcd_xyz(path):
    raw = Path(path).read_bytes()
    end = raw.index(b"DATA binary\n") + len(b"DATA binary\n")
    header = raw[:end].decode("ascii").splitlines()
    fields = next(l.split()[1:] for l in header if l.startswith("FIELDS"))
    sizes = [int(v) for v in next(l.split()[1:] for l in header if l.startswith("SIZE"))]
    types = next(l.split()[1:] for l in header if l.startswith("TYPE"))
    kind = {("F", 4): "<f4", ("F", 8): "<f8", ("U", 4): "<u4", ("I", 4): "<i4", ("U", 1): "u1", ("U", 2): "<u2"}
    dt = np.dtype([(f, kind[(t, s)]) for f, t, s in zip(fields, types, sizes)])
    a = np.frombuffer(raw[end:], dtype=dt)
    return a["x"].astype(float), a["y"].astype(float), a["z"].astype(float)


def leaf_share(x, y, z, door, floor, up):
    """(share of the leaf's cells seen, share of them more than 10 cm from the hinge)"""
    up = np.asarray(up, dtype=float) / np.linalg.norm(up)
    corners = np.array(door["leaf_corners"], dtype=float)
    # The leaf's bottom edge, hinge to latch, in the plane across "up".
    h = corners[0] - corners[0].dot(up) * up
    l = corners[1] - corners[1].dot(up) * up
    length = float(np.linalg.norm(l - h))
    e = (l - h) / length
    n = np.cross(up, e)
    p = np.stack([x, y, z], 1)
    height = p @ up - floor
    along, off = (p - h) @ e, (p - h) @ n
    sel = (np.abs(off) < 0.06) & (along > 0) & (along < length) & (height > 0.25) & (height < 1.75)
    cells = set(zip((along[sel] / 0.05).astype(int), ((height[sel] - 0.25) / 0.1).astype(int)))
    total = math.ceil(length / 0.05) * 15
    beyond = sum(1 for a, _ in cells if a >= 2)  # cells starting 10 cm or more from the hinge
    return len(cells) / total, beyond / total


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--bin", default=os.environ.get("DSR_BIN", str(Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin")))
    args = ap.parse_args()
    shares = []
    for truth_path in sorted(Path(args.dir).glob("*.json")):
        if truth_path.name.endswith(".report.json"):
            continue
        prefix = str(truth_path)[: -len(".json")]
        res = subprocess.run([str(Path(args.bin) / "door_state_eval"), "--in-view-only", f"{prefix}.json",
                              f"{prefix}.report.json"], check=True, capture_output=True, text=True)
        missed = json.loads(res.stdout)["missed_truth"]
        if not missed:
            continue
        truth = json.loads(truth_path.read_text())
        x, y, z = read_pcd_xyz(f"{prefix}.pcd")
        for i in missed:
            d = truth["doors"][i]
            share, beyond = leaf_share(x, y, z, d, truth["floor"], truth.get("up", [0, 0, 1]))
            shares.append(share)
            print(f"{Path(prefix).name} door {i}: {d['state']} {d['opening_angle_deg']:.0f} deg "
                  f"{d['swing']}: leaf cells seen {share:.2f} ({beyond:.2f} beyond 10 cm of the hinge)")
    if shares:
        print(f"missed doors: {len(shares)}; leaf cells seen <= 0.12: {sum(s <= 0.12 for s in shares)}", file=sys.stderr)


if __name__ == "__main__":
    main()
