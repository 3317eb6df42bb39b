#!/usr/bin/env python3
"""make soak-drive, the listener: while a drive bag plays in a loop through
the nodelet (use_sim_time, `rosbag play --clock --loop`), watches for
SECONDS of wall time and records, at the start and at every tenth of the run,
the resident memory (VmRSS) of the process PID, the tracked_doors and doors
messages received so far, the doors in the last tracked_doors message, the
loops of the bag (the clock going back) and the distinct door ids seen.
At the end compares the last tracked_doors message of each loop with the
drive's truth (a door within 0.5 m of a true door's opening centre, in its
state). Prints a table and writes JSON; exits 1 when the process died or
no tracked_doors message came in the last tenth of the run.

  soak_drive_monitor.py --seconds S --pid PID --truth TRUTH.json --json OUT.json
"""
import argparse, json, math, sys, threading, time
import rospy
from rosgraph_msgs.msg import Clock
from door_state_recognition.msg import DoorStateArray

STATES = {0: "closed", 1: "semi_open", 2: "open", 3: "not_closed"}


def rss_mib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def score(msg, truth):
    """(doors in the right state, doors found, false doors) of one tracked_doors message."""
    doors = truth["doors"]
    right = found = 0
    used = set()
    for d in doors:
        oc = d["opening_center"]
        best = None
        for i, m in enumerate(msg.doors):
            dist = math.hypot(m.opening_center.x - oc[0], m.opening_center.y - oc[1])
            if dist < 0.5 and (best is None or dist < best[0]):
                best = (dist, i)
        if best is None:
            continue
        used.add(best[1])
        found += 1
        right += STATES.get(msg.doors[best[1]].state) == d["state"]
    return right, found, len(msg.doors) - len(used)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, required=True)
    ap.add_argument("--pid", type=int, required=True)
    ap.add_argument("--truth", required=True)
    ap.add_argument("--json", required=True)
    a = ap.parse_args()
    truth = json.load(open(a.truth))
    rospy.init_node("soak_drive_monitor", anonymous=True)
    lock = threading.Lock()
    s = {"tracked": 0, "doors": 0, "last": None, "last_at": None, "ids": set(), "loops": 0,
         "clock": None, "loop_ends": []}

    def on_tracked(msg):
        with lock:
            s["tracked"] += 1
            s["last"], s["last_at"] = msg, time.monotonic()
            s["ids"].update(m.id for m in msg.doors)

    def on_doors(msg):
        with lock:
            s["doors"] += 1

    def on_clock(msg):
        t = msg.clock.to_sec()
        with lock:
            if s["clock"] is not None and t < s["clock"] - 1.0:
                s["loops"] += 1
                if s["last"] is not None:  # the last tracked_doors of the loop that ended
                    s["loop_ends"].append(score(s["last"], truth))
            s["clock"] = t

    rospy.Subscriber("/tracked_doors", DoorStateArray, on_tracked, queue_size=5)
    rospy.Subscriber("/doors", DoorStateArray, on_doors, queue_size=5)
    rospy.Subscriber("/clock", Clock, on_clock, queue_size=50)
    start = time.monotonic()
    rows = []

    def sample(label):
        with lock:
            last = s["last"]
            rows.append({"at": label, "seconds": round(time.monotonic() - start, 1), "rss_mib": rss_mib(a.pid),
                         "tracked_msgs": s["tracked"], "doors_msgs": s["doors"], "loops": s["loops"],
                         "tracked_now": len(last.doors) if last else 0, "distinct_ids": len(s["ids"])})
        r = rows[-1]
        rss = f"{r['rss_mib']:.0f}" if r["rss_mib"] is not None else "gone"
        print(f"  {r['at']:>5} {r['seconds']:7.0f} s  RSS {rss:>5} MiB  tracked_doors {r['tracked_msgs']:6d}  "
              f"doors {r['doors_msgs']:6d}  loops {r['loops']:4d}  tracked now {r['tracked_now']:2d}  "
              f"ids {r['distinct_ids']}", flush=True)

    sample("start")
    ok = True
    for k in range(1, 11):
        while time.monotonic() - start < a.seconds * k / 10 and not rospy.is_shutdown():
            time.sleep(0.5)
        before = rows[-1]["tracked_msgs"]
        sample(f"{k}/10")
        if rows[-1]["rss_mib"] is None:
            print("soak_drive: the nodelet's process is gone", file=sys.stderr)
            ok = False
            break
        if rows[-1]["tracked_msgs"] == before:
            print(f"soak_drive: no tracked_doors message in tenth {k}", file=sys.stderr)
            ok = False
    with lock:
        ends = list(s["loop_ends"])
    n_true = len(truth["doors"])
    summary = {"seconds": a.seconds, "rows": rows, "true_doors": n_true, "loops": len(ends),
               "loop_ends": [{"right": r, "found": f, "false": x} for r, f, x in ends]}
    if ends:
        rights = [r for r, _, _ in ends]
        falses = [x for _, _, x in ends]
        print(f"  last tracked_doors of each of {len(ends)} loops: doors right {min(rights)}-{max(rights)} of "
              f"{n_true}, false doors {min(falses)}-{max(falses)}")
    rss = [r["rss_mib"] for r in rows[1:] if r["rss_mib"] is not None]
    if rss:
        print(f"  RSS over the tenths: {min(rss):.0f}-{max(rss):.0f} MiB (start {rows[0]['rss_mib']:.0f})")
    with open(a.json, "w") as f:
        json.dump(summary, f, indent=1)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
