#!/usr/bin/env python3
"""End to end: urlab_client as gymnasium sees it (the project's .venv: gymnasium 1.x), against a
real urlab binary and URLab's in-process library:

- importing urlab_client registers one URLab/*-v0 id per bundled task, and gymnasium's
  check_env passes on each (gymnasium.make: its own `urlab run --envs 1`) with none of its
  warnings; make_vec gives the in-process UrlabVectorEnv with gymnasium's autoreset metadata;
- the vector API driven as gymnasium's documentation drives it: a seeded reset, sampled
  actions, next-step autoreset (the step after an episode's end resets that environment: reward
  0, no flags, a start the same seed gives again), close; infos with their `_key` masks;
- make(id) reset with seed s + i runs what environment i of make_vec(id) reset with seed s runs,
  bit for bit (observations and rewards: the same task on the same physics);
- a falling humanoid is terminated (not truncated), a diverging batch terminated with
  infos["diverged"];
- gymnasium's wrappers: RecordEpisodeStatistics (single and vector) reports each episode's
  return and length, TimeLimit truncates;
- stepping a closed environment (make, make_vec, over_batch, UrlabEnv) raises RuntimeError
  naming it closed; the old option names warn and still work;
- the library is found in the build/ folder of the checkout the package lives in, and the error
  names the paths tried when it is not there.
Usage: gymnasium_e2e.py URLAB_BINARY SOURCE_DIR LIBRARY
"""
import os
import shutil
import subprocess
import sys
import tempfile
import warnings

import numpy as np

URLAB, SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:4])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
os.environ["URLAB_BINARY"] = URLAB
os.environ["URLAB_BATCH_LIBRARY"] = LIBRARY
import gymnasium  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402
from gymnasium.vector import AutoresetMode  # noqa: E402

import urlab_client  # noqa: E402
from urlab_client import UrlabVectorEnv  # noqa: E402
from urlab_client.tasks import TASKS  # noqa: E402
from urlab_process import (PROCS, arm_scene, check, raises, start_announced,  # noqa: E402
                           stop_all)

IDS = sorted(i for i in gymnasium.registry if i.startswith("URLab/"))


def checked():
    """check_env on every registered id, gymnasium's warnings as failures."""
    check(IDS == sorted(f"URLab/{name}-v0" for name in TASKS) and len(IDS) >= 4,
          f"registered ids {IDS}")
    for env_id in IDS:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            env = gymnasium.make(env_id)
            check(isinstance(env.unwrapped, gymnasium.Env), f"{env_id}: {type(env.unwrapped)}")
            check_env(env.unwrapped)
            env.close()
            envs = gymnasium.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
            check(isinstance(envs, UrlabVectorEnv) and envs.num_envs == 2, f"make_vec {envs}")
            check(envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP, f"{envs.metadata}")
            check(envs.single_observation_space == env.observation_space and
                  envs.single_action_space == env.action_space, f"{env_id}: spaces differ")
            envs.close()
    print(f"check_env: {len(IDS)} ids pass without warnings ({', '.join(IDS)})")


def documented_loop():
    """gymnasium's documented vector loop (seeded reset, sampled actions, autoreset, close)."""
    envs = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=3,
                              vectorization_mode="vector_entry_point", max_episode_steps=4)
    observations, infos = envs.reset(seed=42)
    first = observations.copy()
    check(envs.observation_space.contains(observations), "reset obs outside the space")
    check(np.array_equal(infos["_time"], [True] * 3) and np.all(infos["time"] == 0),
          f"reset infos {infos}")
    _ = envs.action_space.seed(42)
    autoreset = np.zeros(envs.num_envs, dtype=bool)
    ended = 0
    for t in range(10):
        actions = envs.action_space.sample()
        observations, rewards, terminations, truncations, infos = envs.step(actions)
        check(envs.observation_space.contains(observations), f"step {t}: obs outside the space")
        check(rewards.shape == (3,) and terminations.dtype == bool, f"step {t}: {rewards}")
        for j in np.flatnonzero(autoreset):  # the step after an episode's end resets it
            check(rewards[j] == 0 and not terminations[j] and not truncations[j] and
                  infos["time"][j] == 0, f"step {t}, env {j}: not an autoreset")
        ended += int(np.count_nonzero(terminations | truncations))
        autoreset = np.logical_or(terminations, truncations)
    check(ended >= 3, f"only {ended} episodes ended in 10 steps of 4-step episodes")
    observations, _ = envs.reset(seed=42)
    check(np.array_equal(observations, first), "the same seed gave another start")
    observations, _ = envs.reset(seed=43)
    check(not np.array_equal(observations, first), "another seed gave the same start")
    envs.close()
    raises(RuntimeError, "closed", lambda: envs.step(envs.action_space.sample()))
    print(f"vector loop: {ended} episodes ended and were reset in 10 steps; seeds repeat")


def same_task(env_id, steps):
    """make(id) with seed 7 + 1 runs environment 1 of make_vec(id) with seed 7, bit for bit."""
    envs = gymnasium.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    env = gymnasium.make(env_id)
    obs_v, _ = envs.reset(seed=7)
    obs_1, _ = env.reset(seed=8)
    check(np.array_equal(obs_v[1], obs_1), f"{env_id}: reset {obs_v[1]} vs {obs_1}")
    rng = np.random.default_rng(0)
    for t in range(steps):
        a = rng.uniform(-1, 1, size=(2,) + env.action_space.shape).astype(np.float32)
        obs_v, r_v, term_v, *_ = envs.step(a)
        obs_1, r_1, term_1, *_ = env.step(a[1])
        check(np.array_equal(obs_v[1], obs_1) and r_v[1] == r_1 and term_v[1] == term_1,
              f"{env_id}, step {t}: make and make_vec differ")
        if term_1:
            break
    env.close()
    raises(RuntimeError, "closed", lambda: env.step(env.action_space.sample()))
    envs.close()


def terminations():
    # The humanoid falls under random torques: terminated (the torso below 1 m), not truncated.
    envs = gymnasium.make_vec("URLab/HumanoidStand-v0", num_envs=2,
                              vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    envs.action_space.seed(0)
    fell = np.zeros(2, dtype=bool)
    for t in range(400):
        _, rewards, terminated, truncated, _ = envs.step(envs.action_space.sample())
        check(not truncated.any(), f"step {t}: truncated {truncated}")
        up = ~fell & ~terminated
        check(np.all(rewards[up] == 1), f"step {t}: alive bonus {rewards}")
        fell |= terminated
        if fell.all():
            break
    check(fell.all(), "the humanoid did not fall in 400 steps (10 s)")
    envs.close()
    fall = t + 1
    # A batch that diverges: terminated, infos["diverged"].
    tmp = tempfile.mkdtemp(prefix="urlab_gym_")
    model = os.path.join(tmp, "unstable.xml")
    with open(model, "w") as f:
        f.write('<mujoco model="unstable"><option timestep="0.05" integrator="Euler"/><worldbody>'
                '<body><joint name="j" type="hinge" axis="0 1 0" stiffness="1e9"/>'
                '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.01"/></body>'
                '</worldbody><actuator><motor joint="j" ctrlrange="-1 1"/></actuator></mujoco>')
    with UrlabVectorEnv.in_process(model, 2, log_level="error") as envs:
        envs.reset(seed=0)
        for t in range(3):
            _, _, terminated, truncated, infos = envs.step(np.ones((2, 1)))
            if terminated.any():
                break
        check(terminated.all() and not truncated.any() and infos["diverged"].all() and
              infos["_diverged"].all(), f"divergence: {terminated} {truncated} {infos}")
    print(f"terminated: the humanoid fell within {fall} steps; a divergence ended as terminated")


def wrappers():
    # One environment: TimeLimit (from the id, here 6 steps) and RecordEpisodeStatistics.
    env = gymnasium.wrappers.RecordEpisodeStatistics(
        gymnasium.make("URLab/QuadrupedWalk-v0", max_episode_steps=6))
    env.reset(seed=1)
    total, steps, truncated = 0.0, 0, False
    while not truncated:
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        total, steps = total + reward, steps + 1
        check(not terminated, "the quadruped fell in 6 steps")
    check(steps == 6 and np.isclose(info["episode"]["r"], total) and info["episode"]["l"] == 6,
          f"RecordEpisodeStatistics: {info.get('episode')} for a return of {total} in {steps}")
    env.close()
    # Vector: gymnasium.wrappers.vector.RecordEpisodeStatistics over the in-process batch.
    envs = gymnasium.wrappers.vector.RecordEpisodeStatistics(gymnasium.make_vec(
        "URLab/ArmReach-v0", num_envs=2, vectorization_mode="vector_entry_point",
        max_episode_steps=5))
    envs.reset(seed=3)
    returns, got = np.zeros(2), []
    for _ in range(5):
        _, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 2), np.float32))
        returns += rewards
        if "episode" in infos:
            got.append((infos["episode"]["r"][infos["_episode"]],
                        returns[infos["_episode"]].copy()))
    check(len(got) == 1 and np.allclose(got[0][0], got[0][1]) and got[0][0].size == 2 and
          np.all(got[0][0] < 0), f"vector episode returns {got} (summed {returns})")
    envs.close()
    print(f"wrappers: episode return {total:.3f} over 6 steps (TimeLimit); vector returns "
          f"{got[0][0].round(3).tolist()}")


def closed_and_renamed():
    tmp = tempfile.mkdtemp(prefix="urlab_gym_")
    proc, a = start_announced(URLAB, arm_scene(tmp, "arm.yaml"), "--no-cameras", "--max-speed",
                              "--envs", "2", duration=86400)
    PROCS.append(proc)
    rpc = a["endpoints"]["rpc"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        envs = UrlabVectorEnv.over_batch(rpc, n_steps=3)
    check(envs.envs[0].frame_skip == 3 and any("n_steps= is deprecated" in str(w.message)
                                               for w in caught), f"n_steps: {caught}")
    envs.close()
    raises(RuntimeError, "closed", lambda: envs.step(np.zeros((2, 2))))
    env = urlab_client.UrlabEnv("arm", endpoint=rpc)
    env.close()
    raises(RuntimeError, "closed", lambda: env.step([0.0, 0.0]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with UrlabVectorEnv.in_process(arm_scene(tmp, "raw.yaml"), 1, reset_noise=0.2) as envs:
            check(envs.envs[0].info["reset_noise"] == 0.2, f"{envs.envs[0].info}")
    check(any("reset_noise= is deprecated" in str(w.message) for w in caught), f"{caught}")
    print("closed environments raise RuntimeError; n_steps and reset_noise warn and work")


def library_in_checkout():
    """A checkout's build/liburlab_batch.so is found with no urlab on PATH and no variable."""
    tmp = tempfile.mkdtemp(prefix="urlab_checkout_")
    shutil.copytree(os.path.join(SOURCE, "clients", "python", "urlab_client"),
                    os.path.join(tmp, "clients", "python", "urlab_client"),
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(os.path.join(SOURCE, "CMakeLists.txt"), tmp)
    scene = os.path.join(SOURCE, "examples", "scenes", "arm_reach.yaml")
    script = ("import sys; from urlab_client import UrlabVectorEnv\n"
              f"envs = UrlabVectorEnv.in_process({scene!r}, 2)\n"
              "print(envs.envs[0].endpoint); envs.close()\n")
    env = {k: v for k, v in os.environ.items() if k not in ("URLAB_BATCH_LIBRARY",)}
    env["PYTHONPATH"] = os.path.join(tmp, "clients", "python")
    env["PATH"] = "/usr/bin:/bin"

    def run():
        return subprocess.run([sys.executable, "-c", script], env=env, cwd=tmp, text=True,
                              capture_output=True, timeout=120)
    r = run()
    want = os.path.join(tmp, "build", "liburlab_batch.so")
    check(r.returncode != 0 and f"{want} (no such file)" in r.stderr,
          f"without a build: exit {r.returncode}, {r.stderr[-800:]}")
    os.makedirs(os.path.join(tmp, "build"))
    os.symlink(LIBRARY, want)
    r = run()
    check(r.returncode == 0 and "in-process:" in r.stdout, f"with build/: {r.stderr[-800:]}")
    print("the library is found in the checkout's build/ (and named when it is not there)")


def main():
    try:
        checked()
        documented_loop()
        for env_id in ("URLab/ArmReach-v0", "URLab/HumanoidStand-v0"):
            same_task(env_id, 40)
        print("make(id) with seed s + 1 ran environment 1 of make_vec(id) with seed s, bit for bit")
        terminations()
        wrappers()
        closed_and_renamed()
        library_in_checkout()
    finally:
        stop_all()
    print("gymnasium_e2e: ok")


if __name__ == "__main__":
    main()
