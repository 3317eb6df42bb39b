#!/usr/bin/env python3
"""make demo: the doors a report found next to the simulator's truth, and for
every door missed or reported only as a bound, one line saying why.

  scripts/demo_table.py TRUTH.json REPORT.json SCORE.json CLOUD.pcd

SCORE.json is door_state_eval's output for the pair. Why a door is missed is
told from the scan itself: the share of the leaf's 5 x 10 cm cells holding a
point of the scan near the leaf's true plane (scripts/leaf_visibility.py).
"""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from leaf_visibility import leaf_share, read_pcd_xyz  # noqa: E402


def why_missed(door, share, beyond):
    how = ("swung away behind its wall" if door["swing"] == "away_from_viewer"
           else "seen edge-on or hidden by what stands in front")
    if share <= 0.12:
        return (f"its leaf is out of the scanner's sight ({100 * share:.0f} % of its cells seen: {how}), and free "
                f"space does not bound it at unseen_leaf_min_bound_deg (90) or more; a station beyond the door would see it")
    if share < 0.35:
        return (f"only {100 * share:.0f} % of its leaf's cells were seen ({how}), below the share a leaf needs "
                f"(min_leaf_coverage, 35 % where the wall is densely sampled), and free space does not bound it at 90 deg or more")
    return (f"its leaf was seen ({100 * share:.0f} % of its cells, {100 * beyond:.0f} % beyond 10 cm of the hinge) "
            f"but no doorway or leaf fit passed: door_state_cli --verbose prints the decision on each candidate")


def main():
    truth, report, score = (json.load(open(f)) for f in sys.argv[1:4])
    cloud = sys.argv[4]
    by_truth = {m["truth_index"]: m for m in score["matches"]}
    xyz = None
    print(f"   {'truth':26s} {'found':30s} {'angle error':>11s} {'hinge error':>11s}")
    notes = []
    for i, d in enumerate(truth["doors"]):
        t = f"door {i}: {d['state']} {d['opening_angle_deg']:.1f} deg"
        m = by_truth.get(i)
        if m:
            f = report["doors"][m["report_index"]]
            bound = f.get("angle_is_lower_bound", False)
            found = f"{f['state']} {'>= ' if bound else ''}{f['opening_angle_deg']:.1f} deg (id {f['id']})"
            ok = "" if f["state"] == d["state"] else "  state wrong"
            print(f"   {t:26s} {found:30s} {m['angle_error_deg']:7.2f} deg {100 * m['hinge_error_m']:7.1f} cm{ok}")
            if f["state"] == "not_closed":
                notes.append(f"door {i} is not_closed: its leaf is out of sight and the doorway is seen through; "
                             f"the angle is a lower bound (no viewpoint to bound it further)")
            elif bound:
                notes.append(f"door {i} is a lower bound: its leaf was not seen; rays through the doorway rule out "
                             f"every leaf position short of {f['opening_angle_deg']:.0f} deg, so it is open at least that far")
        else:
            print(f"   {t:26s} {'not found':30s}")
            if xyz is None:
                xyz = read_pcd_xyz(cloud)
            share, beyond = leaf_share(*xyz, d, truth["floor"], truth.get("up", [0, 0, 1]))
            notes.append(f"door {i} missed: " + why_missed(d, share, beyond))
    for j in score["unmatched_report"]:
        f = report["doors"][j]
        print(f"   (reported, matches no true door: id {f['id']} {f['state']} {f['opening_angle_deg']:.1f} deg)")
    acc = score["state_accuracy"]
    print(f"   precision {score['precision']:.2f}, recall {score['recall']:.2f}, state accuracy "
          f"{'-' if acc is None else f'{acc:.2f}'}")
    for n in notes:
        print(f"   why: {n}")
    states_true = {d["state"] for d in truth["doors"]}
    states_found = {report["doors"][m["report_index"]]["state"] for m in score["matches"]
                    if report["doors"][m["report_index"]]["state"] == truth["doors"][m["truth_index"]]["state"]}
    print(f"   states in the scene: {', '.join(sorted(states_true))}; found right: {', '.join(sorted(states_found)) or 'none'}")


if __name__ == "__main__":
    main()
