#!/usr/bin/env python3
"""Trace the lifts of a folder of `grasp eval --record DIR` recordings.

For every recorded episode it reads the frames of the lift (stage `lift`) and prints one
row: the agent, object, trial, outcome; at the lift's start the normal force of each
distal phalanx on the object (FF MF RF LF TH, N), the whole hand's force and the summed
torque levels of the 20 actuators; through the lift the smallest hand force, how far the
object slid in the hand's frame (mm, lift start to end) and turned (deg), and the lift
height at which the hand last touched the object (`left at`, `-` while still held).
The hand's frame is the pose of hand collider 0 (the first collider of the hand's
root body, which the lift carries), so the slide is the object's motion against the hand. Then the means per agent
and object. Usage: trace.py DIR [--rows]
"""
import glob, json, math, sys, os
from collections import defaultdict


def quat_rot(q, v):
    x, y, z, w = q
    # v' = q v q*
    ix = w * v[0] + y * v[2] - z * v[1]
    iy = w * v[1] + z * v[0] - x * v[2]
    iz = w * v[2] + x * v[1] - y * v[0]
    iw = -x * v[0] - y * v[1] - z * v[2]
    return [ix * w + iw * -x + iy * -z - iz * -y,
            iy * w + iw * -y + iz * -x - ix * -z,
            iz * w + iw * -z + ix * -y - iy * -x]


def inv(q):
    return [-q[0], -q[1], -q[2], q[3]]


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz]


def in_palm(palm, obj):
    d = [obj[i] - palm[i] for i in range(3)]
    p = quat_rot(inv(palm[3:]), d)
    q = qmul(inv(palm[3:]), obj[3:])
    return p, q


def angle(q1, q2):
    d = qmul(inv(q1), q2)
    return math.degrees(2 * math.acos(min(1.0, abs(d[3]))))


def trace(path):
    r = json.load(open(path))
    lift = [f for f in r["frames"] if f["stage"] == "lift"]
    if not lift:
        return None
    f0, f1 = lift[0], lift[-1]
    p0, q0 = in_palm(f0["hand"][0], f0["object"])
    p1, q1 = in_palm(f1["hand"][0], f1["object"])
    slip = 1000 * math.dist(p0, p1)
    turn = angle(q0, q1)
    left = None
    for f in lift:
        if f["hand_force"] > 0.01:
            left = None
        elif left is None:
            left = f["lift"]
    return dict(agent=r["agent"], object=r["object"], seed=r["seed"],
                success=r["summary"]["success"], tips=f0.get("tip_force", [0] * 5),
                hand=f0.get("hand_force", 0), torque=sum(f0["torque_level"]),
                min_hand=min(f["hand_force"] for f in lift), slip=slip, turn=turn,
                left=left)


def main():
    d = sys.argv[1]
    rows = [t for p in sorted(glob.glob(os.path.join(d, "*.json"))) if (t := trace(p))]
    if "--rows" in sys.argv:
        print("agent\tobject\tseed\tsuccess\ttips_N(FF,MF,RF,LF,TH)\thand_N\ttorque_sum\tmin_hand_N\tslip_mm\tturn_deg\tleft_at_m")
        for t in rows:
            print("\t".join(map(str, [t["agent"], t["object"], t["seed"], t["success"],
                                      ",".join(f"{x:.1f}" for x in t["tips"]), f"{t['hand']:.1f}",
                                      t["torque"], f"{t['min_hand']:.2f}", f"{t['slip']:.1f}",
                                      f"{t['turn']:.1f}", "-" if t["left"] is None else f"{t['left']:.3f}"])))
    g = defaultdict(list)
    for t in rows:
        g[(t["agent"], t["object"])].append(t)
    print("agent | object | held | tip forces at lift start, N (FF MF RF LF TH) | hand N | torque-level sum | tips touching | slip mm | turn deg | dropped at lift height (median, failed)")
    for (a, o), ts in sorted(g.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        n = len(ts)
        m = lambda k: sum(t[k] for t in ts) / n
        tips = [sum(t["tips"][i] for t in ts) / n for i in range(5)]
        touching = sum(sum(1 for x in t["tips"] if x > 0.05) for t in ts) / n
        lefts = sorted(t["left"] for t in ts if not t["success"] and t["left"] is not None)
        med = f"{1000 * lefts[len(lefts) // 2]:.0f} mm ({len(lefts)})" if lefts else "-"
        print(f"{a} | {o} | {sum(t['success'] for t in ts)}/{n} | " + " ".join(f"{x:.1f}" for x in tips)
              + f" | {m('hand'):.1f} | {m('torque'):.1f} | {touching:.1f} | {m('slip'):.1f} | {m('turn'):.1f} | {med}")


if __name__ == "__main__":
    main()
