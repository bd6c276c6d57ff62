#!/usr/bin/env python3
"""Trains stable-baselines3's PPO on a URLab task stepped inside this process.

    .venv/bin/python examples/python/sb3_ppo.py                       # URLab/ArmReach-v0
    .venv/bin/python examples/python/sb3_ppo.py --timesteps 2048 --eval-episodes 4   # smoke

The environments are `gymnasium.make_vec(ID, num_envs=N, vectorization_mode=
"vector_entry_point")`: URLab's in-process batch (liburlab_batch.so, from this checkout's build/,
or $URLAB_BATCH_LIBRARY), no server. stable-baselines3 drives its own VecEnv interface, so
GymnasiumVecEnv below adapts a gymnasium VectorEnv to it: SB3 resets an ended episode in the step
that ended it and keeps the last observation in infos["terminal_observation"] (with
"TimeLimit.truncated" for a truncation, which PPO bootstraps from), where gymnasium's vector envs
reset it at the next step (URLab's autoreset mode); the adapter resets the ended environments at
once through the reset option "reset_mask".

Before training and after it, the deterministic policy runs one episode in each environment
from the same seeds (--eval-seed + i); the mean return and length are printed both times. During training
one line per PPO update gives the environment steps, the mean return of the last 100 episodes
and the steps per second. --plot FILE.png draws the learning curve (matplotlib), --csv FILE
writes its points. Needs the project's .venv (tools/install-deps.sh: gymnasium, Debian's
python3-torch, python3-matplotlib and python3-pandas, stable-baselines3 from
tools/requirements-nodeps.txt).
"""
import argparse
import csv
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "clients", "python"))
import gymnasium  # noqa: E402
import urlab_client  # noqa: E402,F401  (registers the URLab/*-v0 ids)
from gymnasium.vector import AutoresetMode  # noqa: E402
from stable_baselines3.common.vec_env import VecEnv  # noqa: E402


class GymnasiumVecEnv(VecEnv):
    """A gymnasium.vector.VectorEnv as a stable-baselines3 VecEnv (one object stepping every
    environment: no per-environment wrappers). Autoreset modes: next-step and disabled (the
    ended environments are reset at once with options={"reset_mask": ended}; the vector env
    must take that option, as gymnasium's own and URLab's do), same-step (infos["final_obs"]
    holds the last observation)."""

    def __init__(self, venv):
        self.venv = venv
        self._mode = venv.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
        self._actions = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    def reset(self):
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        options = self._options[0] or None  # the same options for every environment
        obs, infos = self.venv.reset(seed=seeds, options=options)
        self.reset_infos = self._split(infos)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions):
        self._actions = actions

    def step_wait(self):
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        obs = np.array(obs, copy=True)
        ended = np.logical_or(terminated, truncated)
        out = self._split(infos)
        if ended.any():
            final = infos.get("final_obs") if self._mode == AutoresetMode.SAME_STEP else None
            for i in np.flatnonzero(ended):
                out[i]["terminal_observation"] = obs[i].copy() if final is None else final[i]
                out[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            if self._mode != AutoresetMode.SAME_STEP:
                first, reset_infos = self.venv.reset(options={"reset_mask": ended})
                obs[ended] = first[ended]
                for i, info in enumerate(self._split(reset_infos)):
                    if ended[i]:
                        self.reset_infos[i] = info
        return obs, np.asarray(rewards, dtype=np.float32), ended, out

    def _split(self, infos):
        """gymnasium's dict of arrays (with "_key" masks) as one dict per environment (nested
        dicts, such as same-step autoreset's final_info, are left out)."""
        out = [{} for _ in range(self.num_envs)]
        for key, values in infos.items():
            if key.startswith("_") or key == "final_obs" or isinstance(values, dict):
                continue
            mask = infos.get("_" + key, np.ones(self.num_envs, dtype=bool))
            for i in np.flatnonzero(mask):
                out[i][key] = values[i]
        return out

    def close(self):
        self.venv.close()

    def get_attr(self, attr_name, indices=None):
        return [getattr(self.venv, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name, value, indices=None):
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name, *args, indices=None, **kwargs):
        raise NotImplementedError("the environments are one gymnasium VectorEnv: call "
                                  "GymnasiumVecEnv.venv's methods")

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * len(self._get_indices(indices))


def evaluate(model, env, seed):
    """One episode per environment from seeds seed + i with the deterministic policy: the
    returns and lengths (of the first episode each environment ends; the others keep stepping
    meanwhile)."""
    env.seed(seed)
    obs = env.reset()
    n = env.num_envs
    returns, lengths, finished = np.zeros(n), np.zeros(n, dtype=int), np.zeros(n, dtype=bool)
    while not finished.all():
        actions, _ = model.predict(obs, deterministic=True)
        obs, rewards, dones, _ = env.step(actions)
        returns[~finished] += rewards[~finished]
        lengths[~finished] += 1
        finished |= dones
    return returns, lengths


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    p.add_argument("--env-id", default="URLab/ArmReach-v0",
                   help="a registered URLab task (default %(default)s)")
    p.add_argument("--envs", type=int, default=16,
                   help="environments in the in-process batch (default %(default)s)")
    p.add_argument("--threads", type=int, default=1,
                   help="the batch's stepping threads, 0: the cores (default %(default)s)")
    p.add_argument("--timesteps", type=int, default=200_000,
                   help="environment steps to train for, over all environments "
                        "(default %(default)s)")
    p.add_argument("--n-steps", type=int, default=128,
                   help="PPO's rollout length per environment and update (default %(default)s)")
    p.add_argument("--seed", type=int, default=0,
                   help="the policy's and training environments' seed (default %(default)s)")
    p.add_argument("--eval-seed", type=int, default=10_000,
                   help="environment i's evaluation episode starts from this seed + i "
                        "(default %(default)s)")
    p.add_argument("--eval-episodes", type=int, default=None,
                   help="the evaluation's episodes, one per environment (default: --envs); "
                        "must be at most --envs")
    p.add_argument("--torch-threads", type=int, default=1,
                   help="torch's CPU threads (default %(default)s)")
    p.add_argument("--plot", metavar="FILE.png", help="draw the learning curve here")
    p.add_argument("--csv", metavar="FILE", help="write the learning curve's points here")
    p.add_argument("--save", metavar="FILE.zip", help="save the trained policy here")
    args = p.parse_args()
    episodes = args.envs if args.eval_episodes is None else args.eval_episodes
    if not 1 <= episodes <= args.envs:
        p.error(f"--eval-episodes {episodes}: between 1 and --envs ({args.envs})")

    import stable_baselines3
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecMonitor

    torch.set_num_threads(args.torch_threads)
    venv = gymnasium.make_vec(args.env_id, num_envs=args.envs,
                              vectorization_mode="vector_entry_point", threads=args.threads)
    env = VecMonitor(GymnasiumVecEnv(venv))
    print(f"stable-baselines3 {stable_baselines3.__version__}, torch {torch.__version__}, "
          f"gymnasium {gymnasium.__version__}; {args.env_id}: {args.envs} environments in "
          f"process, observation {env.observation_space.shape}, action "
          f"{env.action_space.shape}", flush=True)
    model = PPO("MlpPolicy", env, n_steps=args.n_steps, batch_size=256, n_epochs=10,
                learning_rate=3e-4, gamma=0.99, gae_lambda=0.95, ent_coef=0.0, seed=args.seed,
                device="cpu", verbose=0)

    before, length = (a[:episodes] for a in evaluate(model, env, args.eval_seed))
    print(f"before training: mean return {before.mean():.2f} over {episodes} episodes "
          f"(seeds {args.eval_seed}..{args.eval_seed + episodes - 1}), mean length "
          f"{length.mean():.1f} steps", flush=True)

    curve = []  # (environment steps, wall seconds, mean return of the last 100 episodes)
    start = time.monotonic()

    class Progress(BaseCallback):
        def _on_step(self):
            return True

        def _on_rollout_end(self):
            infos = self.model.ep_info_buffer
            if not infos:
                return
            mean = float(np.mean([e["r"] for e in infos]))
            seconds = time.monotonic() - start
            steps = self.model.num_timesteps
            curve.append((steps, seconds, mean))
            print(f"steps {steps:8d}  mean return {mean:8.2f} (last {len(infos)} episodes)  "
                  f"{steps / seconds:7.0f} steps/s  {seconds:6.1f} s", flush=True)

    model.learn(total_timesteps=args.timesteps, callback=Progress())
    wall = time.monotonic() - start
    after, length = (a[:episodes] for a in evaluate(model, env, args.eval_seed))
    print(f"after training: mean return {after.mean():.2f} over the same {episodes} episodes, "
          f"mean length {length.mean():.1f} steps")
    print(f"trained {model.num_timesteps} environment steps in {wall:.1f} s "
          f"({model.num_timesteps / wall:.0f} steps/s, learning included)")
    print(f"sb3_ppo: env_id={args.env_id} envs={args.envs} steps={model.num_timesteps} "
          f"wall_seconds={wall:.1f} return_before={before.mean():.3f} "
          f"return_after={after.mean():.3f}")
    finite = np.all(np.isfinite(before)) and np.all(np.isfinite(after)) and \
        all(np.isfinite(c[2]) for c in curve)
    if args.save:
        model.save(args.save)
    env.close()
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["env_steps", "wall_seconds", "mean_return_last_100"])
            w.writerows(curve)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4))
        if curve:
            ax.plot([c[0] for c in curve], [c[2] for c in curve], label="training (last 100 "
                    "episodes)")
        ax.axhline(before.mean(), color="grey", linestyle=":", label="evaluation before")
        ax.axhline(after.mean(), color="green", linestyle="--", label="evaluation after")
        ax.set_xlabel("environment steps")
        ax.set_ylabel("mean episode return")
        ax.set_title(f"stable-baselines3 PPO on {args.env_id}\n{args.envs} environments in "
                     f"process, {model.num_timesteps} steps in {wall / 60:.1f} min", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print(f"learning curve: {args.plot}")
    if not finite:
        print("sb3_ppo: a return was not finite", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
