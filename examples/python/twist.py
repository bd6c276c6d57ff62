#!/usr/bin/env python3
"""Sets a legged articulation's twist (its gait controller then trots at it) on a running URLab
found through its announce file (`urlab run SCENE --announce FILE`), and exits.

    urlab run examples/scenes/go2_network.yaml --ports auto --announce go2.json &
    .venv/bin/python examples/python/twist.py go2.json dog --vx 0.6
"""
import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                "clients", "python"))
from urlab_client import StepClient  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("announce", help="the run's announce file (waited for)")
    parser.add_argument("articulation", help="the articulation with a gait controller")
    parser.add_argument("--vx", type=float, default=0.6, help="forward speed, m/s")
    parser.add_argument("--vy", type=float, default=0.0, help="sideways speed, m/s")
    parser.add_argument("--yaw-rate", type=float, default=0.0, help="turn rate, rad/s")
    parser.add_argument("--wait", type=float, default=30.0, help="seconds to wait for the file")
    args = parser.parse_args()
    deadline = time.monotonic() + args.wait
    while True:
        try:
            with open(args.announce) as f:
                endpoint = json.load(f)["endpoints"]["rpc"]
            break
        except (OSError, ValueError, KeyError):
            if time.monotonic() > deadline:
                sys.exit(f"twist.py: no announce file {args.announce} after {args.wait} s")
            time.sleep(0.05)
    with StepClient(endpoint) as sim:
        reply = sim.set_twist(args.articulation, vx=args.vx, vy=args.vy, yaw_rate=args.yaw_rate)
    print(f"{args.articulation}: twist {reply['linear']} m/s, {reply['angular']} rad/s")


if __name__ == "__main__":
    main()
