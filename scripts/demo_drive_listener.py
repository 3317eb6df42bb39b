#!/usr/bin/env python3
"""make demo, the drive: listens to /tracked_doors while a drive bag plays and,
when no message has come for QUIET_S seconds (the bag is over), prints the
last message's doors next to the simulator's truth (door_scene_sim --drive
writes it in `map`, the frame tracked_doors is in): each true door with the
tracked door whose opening centre lies within 0.5 m, then any tracked door
with no true door there (a false door).

  demo_drive_listener.py TRUTH.json [QUIET_S]
"""
import json, math, sys, threading, time
import rospy
from door_state_recognition.msg import DoorStateArray

STATES = {0: "closed", 1: "semi_open", 2: "open", 3: "not_closed"}


def describe(m):
    bound = ">= " if m.angle_is_lower_bound else ""
    return (f"id {m.id}: {STATES.get(m.state, m.state)} {bound}{math.degrees(m.opening_angle):.1f} deg, "
            f"clear width {m.clear_width:.2f} m, seen in {m.observations} clouds")


def main():
    truth = json.load(open(sys.argv[1]))
    quiet = float(sys.argv[2]) if len(sys.argv) > 2 else 8.0
    rospy.init_node("demo_drive_listener", anonymous=True)
    state = {"last": None, "count": 0, "at": None}

    def cb(msg):
        state["last"], state["at"] = msg, time.monotonic()
        state["count"] += 1
        if state["count"] % 10 == 1:
            print(f"   tracked_doors #{state['count']}: {len(msg.doors)} door(s)", flush=True)

    rospy.Subscriber("/tracked_doors", DoorStateArray, cb, queue_size=5)
    start = time.monotonic()
    # Wall clock: under use_sim_time the bag's clock stops with the bag.
    while not rospy.is_shutdown():
        time.sleep(0.5)
        now = time.monotonic()
        if state["at"] is not None and now - state["at"] > quiet:
            break
        if state["at"] is None and now - start > 180:
            print("   no tracked_doors within 180 s: see the nodelet log", file=sys.stderr)
            sys.exit(1)
    msg = state["last"]
    print(f"== the last of {state['count']} tracked_doors messages (frame {msg.header.frame_id}), against the truth")
    used = set()
    for i, d in enumerate(truth["doors"]):
        c = d["opening_center"]
        near = [(math.hypot(m.opening_center.x - c[0], m.opening_center.y - c[1]), k) for k, m in enumerate(msg.doors)]
        near = [x for x in near if x[0] < 0.5]
        found = "not tracked"
        if near:
            k = min(near)[1]
            used.add(k)
            found = describe(msg.doors[k])
        passed = "passed within 3 m" if d.get("passed_within_3m") else "not passed within 3 m"
        print(f"   door {i}: {d['state']:9s} {d['opening_angle_deg']:6.1f} deg ({passed})   ->   {found}")
    for k, m in enumerate(msg.doors):
        if k not in used:
            print(f"   no door there (a false door): {describe(m)} at "
                  f"({m.opening_center.x:.2f}, {m.opening_center.y:.2f})")


if __name__ == "__main__":
    main()
