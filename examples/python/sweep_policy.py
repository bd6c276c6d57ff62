#!/usr/bin/env python3
"""A policy command for `urlab sweep` (examples/sweeps/arm.yaml): drives the cell's server for
the cell's duration with sinusoidal position targets and prints its return as JSON.

The sweep starts it with URLAB_ENDPOINT, URLAB_SERVER_SESSION, URLAB_SEED, URLAB_DURATION and
URLAB_ARTICULATION set; urlab_client.sweep.policy_env() turns them into a UrlabEnv. The reward is
minus the distance of the first joint from its target, so a larger amplitude scores lower.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../clients/python"))
from urlab_client.sweep import policy_env  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--amplitude", type=float, default=0.5, help="radians")
    p.add_argument("--frequency", type=float, default=1.0, help="Hz")
    args = p.parse_args()
    env, obs, info, duration = policy_env(frame_skip=10, reset_noise_scale=0.05,
                                          reward_fn=lambda o, a, i: -abs(o["qpos"][0] - a[0]))
    with env:
        ret, steps = 0.0, 0
        while info["time"] < duration:
            target = args.amplitude * np.sin(2 * np.pi * args.frequency * info["time"])
            action = np.clip(np.full(env.action_space.shape, target), env.action_space.low,
                             env.action_space.high)
            obs, reward, terminated, truncated, info = env.step(action)
            ret += reward
            steps += 1
    print(json.dumps({"return": round(ret, 6), "steps": steps, "final_time": info["time"]}))


if __name__ == "__main__":
    main()
