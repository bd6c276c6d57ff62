#!/usr/bin/env python3
"""Learns to reach: PPO (PyTorch) drives a servo arm's tip to random targets through
UrlabVectorEnv, over several URLab servers started here.

    .venv/bin/python examples/python/learn_reach.py --urlab ./build/urlab
    .venv/bin/python examples/python/learn_reach.py --urlab ./build/urlab --updates 3  # smoke

Needs the project's .venv (tools/install-deps.sh: gymnasium, Debian's python3-torch). Each update
collects `--steps` steps from each of `--envs` environments (each its own `urlab run` of
examples/scenes/arm_reach.yaml in lockstep, ports chosen by the system), then improves a small
Gaussian policy with PPO's clipped objective. Every update prints one line (mean episode return,
mean final distance to the target, environment steps per second); `--plot FILE.png` writes the
learning curve (matplotlib, optional), `--csv FILE` the same figures as a table.

The task (written here, on top of the environment): at each reset the target is drawn from the
environment's seeded generator in front of the arm, in its plane, within reach; the observation
is the joint angles and velocities, the tip position and the target; the reward is minus the distance
from the tip to the target at each step (metres), so a return of -2 over an episode of 20 steps
(1 s; each step holds the action for 25 physics steps) means 10 cm on average.
"""
import argparse
import csv
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "clients", "python"))
from gymnasium import spaces  # noqa: E402
from urlab_client import UrlabEnv, UrlabVectorEnv  # noqa: E402
from urlab_client.cluster import start_server  # noqa: E402

SHOULDER = np.array([0.0, 1.1])  # the shoulder's (x, z) in the arm's plane (servo_arm.xml)
UPPER, FORE = 0.4, 0.35  # link lengths


class ReachEnv(UrlabEnv):
    """The servo arm as a reaching task: a target in the arm's plane joins the observation."""

    def __init__(self, *args, **kwargs):
        self.target = np.array([0.5, 0.0, 1.1])
        super().__init__(*args, **kwargs)
        self.observation_space = spaces.Dict(
            {**dict(self.observation_space.items()),
             "target": spaces.Box(-np.inf, np.inf, shape=(3,), dtype=np.float64)})

    def _observation(self, reply):
        # The target rides in the articulation's part of the reply, so it is in the observation
        # (and checked against observation_space) like every field the server sends.
        reply["per_articulation"][self.articulation]["target"] = self.target.copy()
        return super()._observation(reply)

    def receive_reset(self):
        # A point in front of the arm, 0.3 to 0.7 m from the shoulder, from 57 degrees below its
        # height to 69 degrees above (clear of the pedestal, within the motors' strength).
        radius = self.np_random.uniform(0.3, 0.7)
        angle = self.np_random.uniform(-1.0, 1.2)
        x, z = SHOULDER + radius * np.array([math.cos(angle), math.sin(angle)])
        self.target = np.array([x, 0.0, z])
        return super().receive_reset()

    def compute_reward(self, obs, action, info):
        return -float(np.linalg.norm(obs["sensors"]["tip_pos"] - self.target))


def flat(obs):
    """The batched Dict observation as one (n, 13) float32 array for the networks: joint
    angles, scaled velocities, tip, target and the tip's offset to the target."""
    tip, target = obs["sensors"]["tip_pos"], obs["target"]
    return np.concatenate([obs["qpos"], obs["qvel"] * 0.1, tip, target, (target - tip) * 3],
                          axis=1).astype(np.float32)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--urlab", default=os.path.join(ROOT, "build", "urlab"), help="the urlab binary")
    p.add_argument("--envs", type=int, default=4, help="environments, one server each (4)")
    p.add_argument("--steps", type=int, default=100, help="steps per environment per update (100)")
    p.add_argument("--updates", type=int, default=150, help="PPO updates (150)")
    p.add_argument("--episode", type=int, default=20, help="steps per episode (20 = 1 s)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--plot", help="write the learning curve to this PNG")
    p.add_argument("--csv", help="write the per-update figures to this CSV")
    args = p.parse_args()

    import torch
    from torch import nn
    torch.manual_seed(args.seed)
    torch.set_num_threads(1)

    scene = os.path.join(ROOT, "examples", "scenes", "arm_reach.yaml")
    servers = [start_server(args.urlab, scene, ("--no-cameras", "--max-speed"))
               for _ in range(args.envs)]
    envs = UrlabVectorEnv([ReachEnv("arm", endpoint=info["endpoints"]["rpc"], frame_skip=25,
                                    max_episode_steps=args.episode, observations="standard")
                           for _, info in servers])
    try:
        return train(args, envs, torch, nn)
    finally:
        envs.close()
        for proc, _ in servers:
            proc.terminate()
            proc.wait(timeout=30)


def train(args, envs, torch, nn):
    n = envs.num_envs
    low = torch.tensor(envs.single_action_space.low, dtype=torch.float32)
    high = torch.tensor(envs.single_action_space.high, dtype=torch.float32)
    obs, _ = envs.reset(seed=args.seed)
    obs_dim, act_dim = flat(obs).shape[1], low.numel()

    def mlp(out):
        return nn.Sequential(nn.Linear(obs_dim, 64), nn.Tanh(), nn.Linear(64, 64), nn.Tanh(),
                             nn.Linear(64, out))
    actor, critic = mlp(act_dim), mlp(1)
    log_std = nn.Parameter(torch.full((act_dim,), -1.5))
    opt = torch.optim.Adam([*actor.parameters(), *critic.parameters(), log_std], lr=1e-3)

    def to_action(raw):  # the policy's unbounded output squashed into the joints' ranges
        return low + (high - low) * (torch.tanh(raw) + 1) / 2

    x = torch.from_numpy(flat(obs))
    history, returns, finals = [], [], []
    ep_return = np.zeros(n)
    skip = np.zeros(n, dtype=bool)  # next-step autoreset: this step only resets the env
    started = time.monotonic()
    for update in range(1, args.updates + 1):
        xs, raws, logps, rewards, dones, values, masks = [], [], [], [], [], [], []
        t0 = time.monotonic()
        for _ in range(args.steps):
            with torch.no_grad():
                mean = actor(x)
                dist = torch.distributions.Normal(mean, log_std.exp())
                raw = dist.sample()
                logp = dist.log_prob(raw).sum(-1)
                value = critic(x).squeeze(-1)
            obs, reward, term, trunc, info = envs.step(to_action(raw).numpy().astype(np.float64))
            xs.append(x)
            raws.append(raw)
            logps.append(logp)
            values.append(value)
            masks.append(torch.from_numpy(~skip))  # autoreset steps carry no experience
            rewards.append(torch.tensor(reward, dtype=torch.float32))
            done = np.logical_or(term, trunc)
            dones.append(torch.from_numpy(done.astype(np.float32)))
            ep_return += np.where(skip, 0.0, reward)
            for i in np.flatnonzero(done):
                returns.append(ep_return[i])
                finals.append(-reward[i])
                ep_return[i] = 0.0
            skip = done
            x = torch.from_numpy(flat(obs))
        rate = n * args.steps / (time.monotonic() - t0)
        with torch.no_grad():
            next_value = critic(x).squeeze(-1)
        # Generalised advantage estimation (gamma 0.99, lambda 0.95), episode ends cut it.
        adv, gae = [], torch.zeros(n)
        for t in reversed(range(args.steps)):
            nv = next_value if t == args.steps - 1 else values[t + 1]
            nonterminal = 1.0 - dones[t]
            delta = rewards[t] + 0.99 * nv * nonterminal - values[t]
            gae = delta + 0.99 * 0.95 * nonterminal * gae
            adv.insert(0, gae)
        b_x, b_raw = torch.cat(xs), torch.cat(raws)
        b_logp, b_adv = torch.cat(logps), torch.cat(adv)
        b_ret = b_adv + torch.cat(values)
        keep = torch.cat(masks)
        b_x, b_raw, b_logp, b_adv, b_ret = (t[keep] for t in (b_x, b_raw, b_logp, b_adv, b_ret))
        b_adv = (b_adv - b_adv.mean()) / (b_adv.std() + 1e-8)
        for _ in range(10):
            for idx in torch.randperm(len(b_x)).split(128):
                dist = torch.distributions.Normal(actor(b_x[idx]), log_std.exp())
                ratio = (dist.log_prob(b_raw[idx]).sum(-1) - b_logp[idx]).exp()
                policy_loss = -torch.min(ratio * b_adv[idx],
                                         ratio.clamp(0.8, 1.2) * b_adv[idx]).mean()
                value_loss = (critic(b_x[idx]).squeeze(-1) - b_ret[idx]).pow(2).mean()
                opt.zero_grad()
                (policy_loss + 0.5 * value_loss).backward()
                opt.step()
        # The episodes that ended during this update's collection.
        mean_return = float(np.mean(returns)) if returns else float("nan")
        final = float(np.mean(finals)) if finals else float("nan")
        returns, finals = [], []
        history.append((update, n * args.steps * update, mean_return, final, rate))
        print(f"update {update:3d}/{args.updates}  env steps {n * args.steps * update:7d}  "
              f"return {mean_return:7.2f}  final distance {final * 100:5.1f} cm  "
              f"{rate:6.0f} env steps/s", flush=True)
    print(f"trained {len(history)} updates in {time.monotonic() - started:.0f} s; "
          f"return {history[0][2]:.2f} -> {history[-1][2]:.2f}")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["update", "env_steps", "mean_return", "final_distance_m", "steps_per_s"])
            w.writerows(history)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 3.5), dpi=120)
        ax.plot([h[1] for h in history], [h[2] for h in history], marker="o", ms=3)
        ax.set_xlabel("environment steps")
        ax.set_ylabel("mean episode return")
        ax.set_title(f"PPO reaching with the servo arm ({n} URLab servers)")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.plot)
        print(f"learning curve: {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
