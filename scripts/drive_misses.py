#!/usr/bin/env python3
"""What the last tracked_doors of simulated drives got wrong, door by door.

Reads the JSON of `door_state_drive_eval --verbose` (one file or several) and
prints, per file, the figures (passed doors right, false doors, drives
without one, wrong doors by cause), then each passed door not right: its
drive's seed, the truth (state, angle), what was tracked (state, angle,
observations), whether the leaf was seen (largest share of it in one cloud)
and how near the robot came; then each false door with its observations and
the spread of the positions that saw it. Compare two runs with the same
seeds (before and after a change) by giving both files.

  door_state_drive_eval --sensor rgbd --seeds 1000-1019 --verbose > rgbd.json
  scripts/drive_misses.py rgbd.json [other.json ...]
"""
import json
import sys


def report(path):
    d = json.load(open(path))
    print(f"{path}: {d['sensor']} {d['seeds']}: passed right {d['passed_right']}/{d['passed_doors']}, "
          f"false doors {d['false_doors']} (drives without {d['drives_without_false_door']}/{d['drives']}), "
          f"wrong by cause {d.get('wrong_by_cause', {})}")
    for p in d.get("per_drive", []):
        for x in p["doors"]:
            if not x["passed"] or x["right"]:
                continue
            got = (f"{x['state']} {x['angle_deg']:.1f}{' (bound)' if x.get('angle_is_lower_bound') else ''}, "
                   f"{x['observations']} clouds") if x["matched"] else "nothing"
            print(f"  {p['seed']} door {x['door']}: {x['why'] or 'wrong'}; truth {x['truth_state']} "
                  f"{x['truth_angle_deg']:.1f}, tracked {got}; leaf share {x['leaf_share_max']:.2f}, "
                  f"robot within {x['min_distance_m']:.2f} m")
        for t in p.get("false_tracks", []):
            c = t["opening_center"]
            print(f"  {p['seed']} false door: {t['state']} {t['angle_deg']:.1f} at ({c[0]:.2f}, {c[1]:.2f}), "
                  f"{t['observations']} clouds from positions {t['spread_m']:.2f} m apart")
    if "per_drive" not in d:
        print("  (no per-drive lines: run door_state_drive_eval with --verbose)")


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        sys.exit(0 if len(sys.argv) >= 2 else 2)
    for f in sys.argv[1:]:
        report(f)
