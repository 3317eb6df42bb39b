#!/usr/bin/env python3
"""Inferred stations against the scanners that made a merged cloud.

usage: station_errors.py DIR [DIR...]

DIR: an eval_sweep.py --out folder (NAME.json truths beside NAME.report.json
reports) of rooms run without a viewpoint. For every true scanner
(truth "sensor_origins"), the horizontal distance to the nearest station of
the report ("stations"); prints their median, quartile and 90th percentile
and how many lie within 0.3 and 0.5 m.
"""
import glob
import json
import sys

import numpy as np


def main(dirs):
    errors = []
    for d in dirs:
        for path in sorted(glob.glob(d + "/*.report.json")):
            truth = json.load(open(path.replace(".report", "")))
            report = json.load(open(path))
            up = np.array(truth.get("up", [0, 0, 1]), dtype=float)
            stations = np.array(report.get("stations") or [], dtype=float).reshape(-1, 3)
            for o in truth.get("sensor_origins", []):
                if len(stations) == 0:
                    errors.append(np.inf)
                    continue
                off = stations - np.array(o, dtype=float)
                off -= np.outer(off @ up, up)
                errors.append(float(np.min(np.linalg.norm(off, axis=1))))
    if not errors:
        print("no report with sensor_origins and stations")
        return 1
    e = np.array(errors)
    print("true scanners %d: nearest station median %.2f m, p75 %.2f, p90 %.2f; within 0.3 m %d, within 0.5 m %d"
          % (len(e), np.median(e), np.percentile(e, 75), np.percentile(e, 90), (e < 0.3).sum(), (e < 0.5).sum()))
    return 0


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        sys.exit(0 if len(sys.argv) >= 2 else 2)
    sys.exit(main(sys.argv[1:]))
