#!/usr/bin/python3
"""Makes a legged robot lie down and stand up again over the streaming topics (docs/protocol.md).

Start the simulator first:   urlab run examples/scenes/go2_network.yaml
Then:                        /usr/bin/python3 examples/python/pd_stand.py

It discovers the robot's actuators, reads its joint angles, folds every leg from where it is to a
lying pose, then unfolds them to a standing pose (joint position targets for the simulator's PD
controller, interpolated over --rise seconds each), holds it, and prints the base height from the
base_state topic. Exits 0 when the robot stood up again from lying.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../clients/python"))
from urlab_client import StreamClient  # noqa: E402

STAND = {"hip": 0.0, "thigh": 0.9, "calf": -1.8}  # radians, per joint kind
LIE = {"hip": 0.0, "thigh": 1.4, "calf": -2.6}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--robot", default="dog")
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--state", help="state endpoint (default tcp://HOST:5555)")
    p.add_argument("--control", help="control endpoint (default tcp://HOST:5556)")
    p.add_argument("--info", help="discovery endpoint (default tcp://HOST:5557)")
    p.add_argument("--rise", type=float, default=1.5, help="seconds to reach each pose")
    p.add_argument("--hold", type=float, default=1.5, help="seconds to hold the standing pose")
    args = p.parse_args()

    with StreamClient(args.host, state=args.state, control=args.control, info=args.info) as c:
        robot = c.discover(expect=[args.robot])[args.robot]
        joints = {a: a + "_joint" for a in robot.actuator_names_short}
        c.poll(timeout=1.0)
        start = {a: c.joint_position(args.robot, j) or 0.0 for a, j in joints.items()}
        base0 = c.state[args.robot]["base_state"]
        print(f"{args.robot}: {len(joints)} actuators, base height {height(c, args.robot):.3f} m")
        lying = move(c, args, joints, start, {a: LIE[a.rsplit("_", 1)[1]] for a in joints},
                     "lying down")
        stand = {a: STAND[a.rsplit("_", 1)[1]] for a in joints}
        standing = move(c, args, joints, {a: LIE[a.rsplit("_", 1)[1]] for a in joints}, stand,
                        "standing up", hold=args.hold)
        print(f"lying {lying:.3f} m, standing {standing:.3f} m")
        return 0 if base0 and standing > lying + 0.05 else 1


def height(c, robot):
    bases = c.state.get(robot, {}).get("base_state", {})
    return next(iter(bases.values()))["pos"][2] if bases else float("nan")


def move(c, args, joints, start, goal, what, hold=0.5):
    """Interpolates the targets from start to goal over --rise s, holds; returns the height."""
    print(what)
    t0 = time.monotonic()
    last_print = -1.0
    while (t := time.monotonic() - t0) < args.rise + hold:
        s = min(1.0, t / args.rise)
        c.send_control(args.robot, {a: start[a] + s * (goal[a] - start[a]) for a in joints})
        c.poll(timeout=0.01)
        if t - last_print >= 0.5:
            print(f"  t={t:4.1f} s  base height {height(c, args.robot):.3f} m")
            last_print = t
    return height(c, args.robot)


if __name__ == "__main__":
    sys.exit(main())
