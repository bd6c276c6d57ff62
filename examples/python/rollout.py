#!/usr/bin/env python3
"""A lockstep rollout loop: collects 10,000 steps of (observation, action) through the step server.

Start the simulator first:   urlab run examples/scenes/go2_network.yaml
Then:                        .venv/bin/python examples/python/rollout.py [--out rollout.npz]

The simulator switches to direct (lockstep) mode: its physics advances only when this script asks,
so no step is lost and the data do not depend on this machine's speed. Each step sends one action
(joint position targets: the standing pose plus a slow sinusoid per leg) and receives the
observation that shows it. Every `--episode` steps the episode is truncated and the robot is reset
to its keyframe. Prints the rate and, with --out, saves qpos, qvel, actions and times with numpy.
Leaving the `with` block releases the simulator, which goes back to running on its own.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../clients/python"))
from urlab_client import UrlabEnv  # noqa: E402

STAND = {"hip": 0.0, "thigh": 0.9, "calf": -1.8}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--robot", default="dog")
    p.add_argument("--endpoint", default="tcp://127.0.0.1:5559", help="the step server")
    p.add_argument("--steps", type=int, default=10000)
    p.add_argument("--episode", type=int, default=2000, help="steps between resets")
    p.add_argument("--keyframe", default="dog_home", help="reset keyframe (full name)")
    p.add_argument("--out", help="save the rollout to this .npz file")
    args = p.parse_args()

    with UrlabEnv(args.robot, endpoint=args.endpoint, keyframe=args.keyframe,
                  max_episode_steps=args.episode) as env:
        names = [n[len(args.robot) + 1:] for n in env.actuators]
        stand = np.array([STAND.get(n.rsplit("_", 1)[-1], 0.0) for n in names])
        phase = np.arange(len(names)) * 0.5
        obs, info = env.reset(seed=0)
        qpos, qvel, actions, times = [], [], [], []
        t0 = time.monotonic()
        for i in range(args.steps):
            action = stand + 0.2 * np.sin(2 * np.pi * 0.5 * (i % args.episode) * 0.002 + phase)
            obs, reward, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                env.reset()
            qpos.append(obs["qpos"])
            qvel.append(obs["qvel"])
            actions.append(action)
            times.append(info["time"])
            if (i + 1) % 2000 == 0:
                rate = (i + 1) / (time.monotonic() - t0)
                print(f"{i + 1:6d} steps  {rate:7.0f} steps/s  base height {obs['qpos'][2]:.3f} m")
        elapsed = time.monotonic() - t0
        print(f"{args.steps} lockstep steps in {elapsed:.2f} s ({args.steps / elapsed:.0f} steps/s)")
        if args.out:
            np.savez(args.out, qpos=np.array(qpos), qvel=np.array(qvel), action=np.array(actions),
                     time=np.array(times))
            print(f"saved {args.out}")
        return 0 if len(qpos) == args.steps else 1


if __name__ == "__main__":
    sys.exit(main())
