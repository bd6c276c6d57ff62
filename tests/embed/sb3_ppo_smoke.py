#!/usr/bin/env python3
"""Smoke test: stable-baselines3 (tools/requirements-nodeps.txt) on a URLab task in process,
through examples/python/sb3_ppo.py's GymnasiumVecEnv over gymnasium.make_vec:

- the adapter keeps SB3's VecEnv contract: an ended episode comes back reset in the same step
  (its first observation, the environment's episode restarted), its last observation in
  infos["terminal_observation"], "TimeLimit.truncated" set for a truncation only; seeds given
  with seed() give the same observations again;
- PPO learns for a few hundred environment steps: it counts them, its episode returns and the
  evaluation's are finite numbers;
- the example's command line runs a short training end to end and prints its summary line.
Usage: sb3_ppo_smoke.py SOURCE_DIR LIBRARY
"""
import importlib.util
import os
import re
import subprocess
import sys

import numpy as np

SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:3])
EXAMPLE = os.path.join(SOURCE, "examples", "python", "sb3_ppo.py")
os.environ["URLAB_BATCH_LIBRARY"] = LIBRARY
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
spec = importlib.util.spec_from_file_location("sb3_ppo", EXAMPLE)
sb3_ppo = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sb3_ppo)

import gymnasium  # noqa: E402
import torch  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.vec_env import VecMonitor  # noqa: E402


def check(cond, message):
    if not cond:
        print(f"FAIL: {message}", file=sys.stderr)
        sys.exit(1)


def adapter_contract():
    # Episodes of 5 steps: several truncations in a few steps.
    venv = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=3,
                              vectorization_mode="vector_entry_point", max_episode_steps=5,
                              threads=1)
    env = sb3_ppo.GymnasiumVecEnv(venv)
    env.seed(11)
    first = env.reset()
    check(first.shape == (3,) + env.observation_space.shape, f"reset obs {first.shape}")
    env.seed(11)
    check(np.array_equal(env.reset(), first), "the same seeds give the same first observations")
    ended_seen = 0
    for t in range(1, 13):
        obs, rewards, dones, infos = env.step(np.zeros((3, 2), dtype=np.float32))
        check(obs.shape == first.shape and rewards.dtype == np.float32 and len(infos) == 3,
              "step's shapes")
        check(np.all(np.isfinite(obs)) and np.all(np.isfinite(rewards)), "finite values")
        for i in range(3):
            if dones[i]:
                ended_seen += 1
                term = infos[i].get("terminal_observation")
                check(term is not None and term.shape == obs[i].shape,
                      f"step {t}: no terminal_observation for env {i}")
                check(infos[i]["TimeLimit.truncated"] is True, f"step {t}: a 5-step episode "
                      "ends truncated")
                check(not np.array_equal(term, obs[i]), f"step {t}: env {i} was not reset")
            else:
                check("terminal_observation" not in infos[i], f"step {t}: a running episode "
                      "has a terminal observation")
    check(ended_seen >= 6, f"only {ended_seen} episode ends in 12 steps of 5-step episodes")
    # After a reset in the same step, the next step continues the new episode (no extra reset:
    # the vector env's own next-step autoreset must not fire on top of the adapter's).
    env.seed(5)
    env.reset()
    for t in range(1, 6):
        _, _, dones, _ = env.step(np.zeros((3, 2), dtype=np.float32))
        check(dones.all() == (t == 5), f"step {t}: dones {dones}")
    for t in range(1, 6):
        _, rewards, dones, _ = env.step(np.zeros((3, 2), dtype=np.float32))
        check(np.all(rewards != 0), f"step {t} of the second episode: reward 0 (a step spent "
              "on a reset)")
        check(dones.all() == (t == 5), f"second episode, step {t}: dones {dones}")
    env.close()
    print(f"GymnasiumVecEnv: same-step resets, terminal observations, truncation flags "
          f"({ended_seen} episode ends)")


def learns_a_little():
    torch.set_num_threads(1)
    venv = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=4,
                              vectorization_mode="vector_entry_point", threads=1)
    env = VecMonitor(sb3_ppo.GymnasiumVecEnv(venv))
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=2, seed=0, device="cpu")
    model.learn(total_timesteps=512)
    check(model.num_timesteps >= 512, f"{model.num_timesteps} steps")
    returns = [e["r"] for e in model.ep_info_buffer]
    check(len(returns) >= 1 and np.all(np.isfinite(returns)), f"episode returns {returns}")
    evaluation, lengths = sb3_ppo.evaluate(model, env, 100)
    check(evaluation.shape == (4,) and np.all(np.isfinite(evaluation)) and
          np.all(evaluation < 0), f"evaluation {evaluation}")
    check(np.all((lengths >= 1) & (lengths <= 100)), f"episode lengths {lengths}")
    env.close()
    print(f"PPO: {model.num_timesteps} steps, {len(returns)} episodes (mean return "
          f"{np.mean(returns):.2f}), evaluation {np.round(evaluation, 2)}")


def command_line():
    r = subprocess.run([sys.executable, EXAMPLE, "--envs", "4", "--timesteps", "512",
                        "--n-steps", "64"], capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"sb3_ppo.py exit {r.returncode}: {r.stderr[-2000:]}")
    line = re.search(r"sb3_ppo: env_id=URLab/ArmReach-v0 envs=4 steps=(\d+) wall_seconds=\S+ "
                     r"return_before=(\S+) return_after=(\S+)", r.stdout)
    check(line is not None, f"no summary line in {r.stdout[-2000:]}")
    check(int(line.group(1)) >= 512 and all(np.isfinite(float(line.group(k))) for k in (2, 3)),
          f"summary {line.group(0)}")
    print(f"sb3_ppo.py: {line.group(0)}")


def main():
    adapter_contract()
    learns_a_little()
    command_line()
    print("sb3_ppo_smoke: ok")


if __name__ == "__main__":
    main()
