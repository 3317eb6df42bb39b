#!/usr/bin/env python3
"""Why are camera doors whose leaf is in view missed, or given a wrong state?

Reads folders written by `eval_sweep.py --sensor rgbd --out DIR`, scores each
frame with `door_state_eval --leaf-in-view-only SHARE`, and for every truth
door so scored that no report matched, or that was matched in a wrong state,
prints one line: the door (state, angle, swing, leaf_in_view), the camera
(height above the floor, pitch, horizontal distance to the doorway), where
the doorway lies in the image (its head above the image's top, a jamb beyond
a side, the foot below the bottom), and the pipeline's stage it failed at:
the door's wall not found (no reported wall within 0.3 m of the doorway), no
doorway candidate on it, or the candidate's decision (door_state_cli
--verbose: "no leaf (...)", "rejected: ..."), or for a wrong state what was
reported. Ends with the counts of each cause, and the false positives
(reports matching no truth door) with where they stand: within 1 m of a
true door, of furniture or a window, or elsewhere.

  scripts/camera_misses.py DIR [DIR ...] [--share S] [--bin BUILD_BIN]
"""
import argparse, collections, json, math, os, re, subprocess, sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
F, W, H = 525.0, 640, 480  # eval_sweep's frames


def pixel(p):
    return F * p[0] / p[2] + (W - 1) / 2.0, F * p[1] / p[2] + (H - 1) / 2.0


def doorway_in_image(door, up):
    """(head above the top, a jamb beyond a side, foot below the bottom) of the doorway's rectangle."""
    up = np.asarray(up, float)
    c, n = np.asarray(door["opening_center"], float), np.asarray(door["wall_normal"], float)
    axis = np.cross(up, n)
    pts = {k: [c + axis * s * door["width"] / 2 + up * z for s in (-1, 1)] for k, z in (("foot", 0.05), ("head", door["height"]))}
    def above(p):  # image row above 0 (or behind the camera)
        return p[2] <= 0 or pixel(p)[1] < 0
    def below(p):
        return p[2] <= 0 or pixel(p)[1] >= H
    head = all(above(p) for p in pts["head"]) or any(above(p) for p in pts["head"])
    foot = any(below(p) for p in pts["foot"])
    side = any(p[2] <= 0 or not 0 <= pixel(p)[0] < W for p in pts["foot"] + pts["head"])
    return head, side, foot


def plane2d(up):
    """Horizontal (right, forward) axes of the camera frame, as door_state_cli's trace prints positions."""
    up = np.asarray(up, float)
    e1 = np.array([1.0, 0, 0]) - up[0] * up
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(up, e1)


def trace(bin_dir, pcd):
    out = subprocess.run([str(Path(bin_dir) / "door_state_cli"), "--up", "-y", "--verbose", "--json", os.devnull, pcd],
                         capture_output=True, text=True, check=True).stderr
    walls, doorways = {}, []
    for line in out.splitlines():
        m = re.match(r"door_state_cli: wall (\d+): point \(([-\d.]+), ([-\d.]+)\) dir \(([-\d.]+), ([-\d.]+)\)", line)
        if m:
            walls[int(m.group(1))] = (np.array([float(m.group(2)), float(m.group(3))]),
                                      np.array([float(m.group(4)), float(m.group(5))]))
            continue
        m = re.match(r"door_state_cli: wall (\d+): doorway s=\[([-\d.]+), ([-\d.]+)\](.*)", line)
        if m:
            p, d = walls[int(m.group(1))]
            s0, s1 = float(m.group(2)), float(m.group(3))
            rest = m.group(4)
            verdict = rest.split("|")[-1].strip() if "|" in rest else rest
            if "no leaf (" in rest:
                verdict = "no leaf (" + rest.split("no leaf (")[1].split(":")[0] + ")"
            doorways.append((p + d * (s0 + s1) / 2, (s1 - s0), verdict.strip()))
    return walls, doorways, out


def horizontal(v, up):
    return float(np.linalg.norm(v - v.dot(up) * up))


def wall_near(report, oc, up):
    """Distance from the doorway's middle to the nearest reported wall (horizontal, within its length)."""
    up = np.asarray(up, float)
    best = math.inf
    for w in report["walls"]:
        p, d = np.asarray(w["line"]["point"], float), np.asarray(w["line"]["direction"], float)
        d = d - d.dot(up) * up
        d /= np.linalg.norm(d)
        q = oc - p
        q = q - q.dot(up) * up
        t = q.dot(d)
        if -0.3 <= t <= w["length"] + 0.3:
            best = min(best, float(np.linalg.norm(q - t * d)))
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--share", type=float, default=0.5)
    ap.add_argument("--bin", default=os.environ.get("DSR_BIN", str(Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin")))
    args = ap.parse_args()
    causes, geometry, right_geometry, scored = collections.Counter(), collections.Counter(), collections.Counter(), 0
    false_positives, fp_where = [], collections.Counter()
    examples = collections.defaultdict(list)
    for d in args.dirs:
        for line in (Path(d) / "pairs.txt").read_text().splitlines():
            gt, rep = line.split()
            res = json.loads(subprocess.run([str(Path(args.bin) / "door_state_eval"), "--leaf-in-view-only", str(args.share),
                                             gt, rep], capture_output=True, text=True, check=True).stdout)
            scored += res["true_doors"]
            wrong = {m["truth_index"]: m for m in res["matches"] if not m["state_correct"]}
            bad = sorted(res["missed_truth"] + list(wrong))
            truth, report = json.loads(Path(gt).read_text()), json.loads(Path(rep).read_text())
            up = np.asarray(truth["up"], float)
            seed = re.search(r"_(\d+)\.json$", gt).group(1)
            for j in res["unmatched_report"]:
                rc = np.asarray(report["doors"][j]["opening_center"], float)
                near_door = min([horizontal(np.asarray(t["opening_center"], float) - rc, up) for t in truth["doors"]] or [math.inf])
                near_decoy = min([horizontal(np.asarray(t["center"], float) - rc, up) for t in truth["decoys"]] or [math.inf])
                where = ("within 1 m of a true door" if near_door <= 1.0 else
                         "within 1 m of furniture or a window" if near_decoy <= 1.0 else "elsewhere")
                fp_where[where] += 1
                false_positives.append(f"{Path(d).name} {seed} report door {j} "
                                       f"({report['doors'][j]['state']} {report['doors'][j]['opening_angle_deg']:.0f} deg): {where}")
            for m in res["matches"]:  # where the doorways of the doors right lie
                if m["state_correct"]:
                    head, side, foot = doorway_in_image(truth["doors"][m["truth_index"]], up)
                    right_geometry["head above the image"] += head
                    right_geometry["jamb beyond a side"] += side
                    right_geometry["foot below the image"] += foot
                    right_geometry["doorway in the image"] += not (head or side or foot)
            if not bad:
                continue
            e1, e2 = plane2d(up)
            walls, doorways, _ = trace(args.bin, gt[: -len(".json")] + ".pcd")
            for i in bad:
                door = truth["doors"][i]
                oc = np.asarray(door["opening_center"], float)
                dist = math.hypot(oc.dot(e1), oc.dot(e2))
                head, side, foot = doorway_in_image(door, up)
                where = [k for k, v in (("head above the image", head), ("jamb beyond a side", side),
                                        ("foot below the image", foot)) if v]
                if i in wrong:
                    m = wrong[i]
                    r = report["doors"][m["report_index"]]
                    cause = "wrong state: reported " + ("not_closed" if m["not_closed"] else r["state"]) + \
                            f" for {door['state']}" + (" (a lower bound)" if m["angle_is_lower_bound"] else "")
                    detail = f"reported {r['state']} {r['opening_angle_deg']:.0f} deg"
                else:
                    near = wall_near(report, oc, up)
                    o2 = np.array([oc.dot(e1), oc.dot(e2)])
                    cands = [c for c in doorways if np.linalg.norm(c[0] - o2) < 0.6]
                    if report["floor"] is None and near > 0.3:
                        cause = "no floor and no wall found"
                    elif near > 0.3:
                        cause = "its wall not found"
                    elif not cands:
                        cause = "no doorway candidate on its wall"
                    else:
                        verdict = min(cands, key=lambda c: np.linalg.norm(c[0] - o2))[2]
                        cause = "candidate " + re.sub(r"\s*\(.*", "", verdict) if verdict.startswith("rejected") else \
                            "candidate: " + verdict
                    detail = f"wall at {near:.2f} m"
                causes[cause] += 1
                for w in where or ["doorway in the image"]:
                    geometry[w] += 1
                name = Path(d).name
                examples[cause].append(f"{name} {seed}")
                print(f"{name} seed {seed} door {i}: {door['state']} {door['opening_angle_deg']:.0f} deg {door['swing']} "
                      f"leaf {door['leaf_in_view']:.2f}; camera {-truth['floor']:.2f} m high, pitch "
                      f"{math.degrees(math.asin(max(-1, min(1, up[2])))):.0f} deg, {dist:.1f} m away; "
                      f"{', '.join(where) or 'doorway in the image'}; {cause}; {detail}")
    print(f"\nscored doors (leaf_in_view >= {args.share:g}): {scored}; missed or wrong: {sum(causes.values())}")
    for c, n in causes.most_common():
        print(f"{n:4d}  {c}  (e.g. {', '.join(examples[c][:4])})")
    print("where the doorway lies (missed or wrong; found in the right state):")
    for c in ("head above the image", "jamb beyond a side", "foot below the image", "doorway in the image"):
        print(f"{geometry[c]:4d} {right_geometry[c]:4d}  {c}")
    print(f"false positives (reports matching no scored door and no door left out): {len(false_positives)}; "
          + ", ".join(f"{n} {w}" for w, n in fp_where.most_common()))
    for f in false_positives:
        print("  " + f)


if __name__ == "__main__":
    main()
