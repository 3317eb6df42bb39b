#!/usr/bin/env python3
"""Waits for DoorStateArray messages on /doors and prints each door next to
the simulator's truth (truth JSON given; doors matched by opening centre)."""
import json, math, sys, threading
import numpy as np
import rospy
from door_state_recognition.msg import DoorStateArray

STATES = {0: "closed", 1: "semi_open", 2: "open", 3: "not_closed"}

def main():
    truth = json.load(open(sys.argv[1]))
    want = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    tr = truth["sensor_to_world"]
    x, y, z, w = tr["rotation_xyzw"]
    R = np.array([[1 - 2*(y*y + z*z), 2*(x*y - z*w), 2*(x*z + y*w)],
                  [2*(x*y + z*w), 1 - 2*(x*x + z*z), 2*(y*z - x*w)],
                  [2*(x*z - y*w), 2*(y*z + x*w), 1 - 2*(x*x + y*y)]])
    t = np.array(tr["translation"])
    doors = [(R @ np.array(d["opening_center"]) + t, d) for d in truth["doors"]]
    rospy.init_node("demo_listener", anonymous=True)
    got = []
    def cb(msg):
        got.append(msg)
        print(f"== DoorStateArray #{len(got)}: stamp {msg.header.stamp.to_sec():.2f}, frame {msg.header.frame_id}, "
              f"{len(msg.doors)} door(s)")
        for centre, d in doors:
            best = min(msg.doors, key=lambda m: math.hypot(m.opening_center.x - centre[0], m.opening_center.y - centre[1]),
                       default=None)
            found = "not found"
            if best and math.hypot(best.opening_center.x - centre[0], best.opening_center.y - centre[1]) < 0.5:
                found = (f"id {best.id}: {STATES.get(best.state, best.state)} {'>= ' if best.angle_is_lower_bound else ''}{math.degrees(best.opening_angle):.1f} deg "
                         f"(confidence {best.confidence:.2f})")
            print(f"   truth {d['state']:9s} {d['opening_angle_deg']:6.1f} deg   ->   {found}")
        if len(got) >= want:
            rospy.signal_shutdown("done")
    rospy.Subscriber("/doors", DoorStateArray, cb, queue_size=5)
    # Wall-clock timeout: under use_sim_time (the bag's clock) a rospy.Timer
    # stops with the bag and would never fire.
    timer = threading.Timer(120, lambda: rospy.signal_shutdown("timeout: no answer from the nodelet"))
    timer.daemon = True
    timer.start()
    rospy.spin()
    if len(got) < want:
        print(f"   only {len(got)} of {want} DoorStateArray messages within 120 s: see the nodelet log", file=sys.stderr)
    sys.exit(0 if len(got) >= want else 1)

if __name__ == "__main__":
    main()
