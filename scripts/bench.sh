#!/usr/bin/env bash
# make bench: wall-clock medians of the simulator and of the pipeline, per
# stage, on simulated scenes with fixed seeds, measured side by side in one
# run. Prints a table and writes build/bench/bench.json.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${DSR_BUILD:-$REPO/build}"
BIN="$BUILD/bin"
OUT="$BUILD/bench"
RUNS="${BENCH_RUNS:-5}"
mkdir -p "$OUT"
/usr/bin/python3 - "$BIN" "$OUT" "$RUNS" <<'PY'
import json, os, statistics, subprocess, sys, time
BIN, OUT, RUNS = sys.argv[1], sys.argv[2], int(sys.argv[3])
cases = [("tls", 100000), ("tls", 400000), ("tls", 1000000), ("rgbd", 307200)]
results = []
print(f"median of {RUNS} runs, {os.cpu_count()} cores; seed 7 for every scene")
print(f"{'case':16s} {'sim ms':>8s} {'pipeline ms':>12s}  per stage (ms)")
for sensor, n in cases:
    prefix = f"{OUT}/{sensor}_{n}"
    sim_ms = []
    for r in range(RUNS):
        t0 = time.perf_counter()
        subprocess.run([f"{BIN}/door_scene_sim", "--quiet", "--sensor", sensor, "--points", str(n), "--seed", "7",
                        "--formats", "pcd,json", "--out", prefix], check=True)
        sim_ms.append(1000 * (time.perf_counter() - t0))
    stages = {}
    up = "-y" if sensor == "rgbd" else "+z"
    for r in range(RUNS):
        out = subprocess.run([f"{BIN}/door_state_cli", "--quiet", "--up", up, f"{prefix}.pcd"], check=True,
                             capture_output=True, text=True).stdout
        for k, v in json.loads(out)["timing_ms"].items():
            stages.setdefault(k, []).append(v)
    med = {k: statistics.median(v) for k, v in stages.items()}
    results.append({"sensor": sensor, "points": n, "sim_ms": statistics.median(sim_ms), "pipeline_ms": med})
    per = " ".join(f"{k} {v:.0f}" for k, v in med.items() if k not in ("total", "read"))
    print(f"{sensor + ' ' + str(n):16s} {statistics.median(sim_ms):8.0f} {med['total']:12.0f}  {per}")
json.dump(results, open(f"{OUT}/bench.json", "w"), indent=1)
print(f"wrote {OUT}/bench.json (pipeline total excludes reading the file)")
PY
