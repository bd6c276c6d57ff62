#!/usr/bin/env python3
"""End to end: UrlabEnv and UrlabVectorEnv against real `urlab run` processes, checked against
gymnasium's documented contract:

- the spaces contain the observations reset and step return, and the action space is the
  actuators' target ranges (the joints' ranges under the PD controller);
- the same seed gives the same episode (initial noise and every observation, bit for bit), and
  another seed another one;
- reward and termination hooks, max_episode_steps truncation, the context manager releasing the
  lease at once;
- a vector env over two servers: batched spaces and observations, next-step autoreset (the step
  after an episode's end resets it, ignores its action, reward 0, no flags), and a server that
  dies ending its episode as truncated and coming back through the replace callback;
- camera images (a stream of the articulation, or "art/stream") and the observation level
  in the observation space.
Usage: gym_env_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import sys
import tempfile

import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient, UrlabEnv, UrlabVectorEnv  # noqa: E402
from urlab_process import PROCS, arm_scene, check, fail, start_announced, stop_all  # noqa: E402


def server(scene, *extra):
    # Live between the envs' leases at --max-speed: a day of simulated time, not 120 s.
    proc, a = start_announced(URLAB, scene, *(extra or ("--no-cameras",)), "--max-speed",
                              duration=86400)
    PROCS.append(proc)
    return proc, a["endpoints"]["rpc"]


def episode(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs["qpos"].copy()]
    for a in actions:
        obs, *_ = env.step(a)
        out.append(np.concatenate([obs["qpos"], obs["qvel"], obs["sensors"]["tip_pos"]]))
    return out


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_gym_")
    scene = arm_scene(tmp, "arm.yaml")
    proc, rpc = server(scene)

    # Spaces and the observation.
    env = UrlabEnv("arm", endpoint=rpc, frame_skip=5, reset_noise_scale=0.1)
    with StepClient(rpc) as c:
        arts = {a["name"]: a for a in c.info["articulations"]}
        joints = {j["name"]: j["range"] for j in arts["arm"]["joints"]}
    want_low = [joints["shoulder"][0], joints["elbow"][0]]
    want_high = [joints["shoulder"][1], joints["elbow"][1]]
    check(env.action_space.shape == (2,) and np.allclose(env.action_space.low, want_low) and
          np.allclose(env.action_space.high, want_high),
          f"action space {env.action_space.low}..{env.action_space.high}, joints {joints}")
    obs, info = env.reset(seed=1)
    check(env.observation_space.contains(obs), f"reset obs outside {env.observation_space}")
    check(set(obs) == {"qpos", "qvel", "ctrl", "act", "sensors"}, f"keys {list(obs)}")
    env.action_space.seed(7)
    for _ in range(10):
        a = env.action_space.sample()
        check(env.action_space.contains(a), f"sampled action {a} outside the space")
        obs, reward, terminated, truncated, info = env.step(a)
        check(env.observation_space.contains(obs), "step obs outside the space")
        check(isinstance(reward, float) and terminated is False and truncated is False,
              f"no task: reward {reward!r}, flags {terminated!r} {truncated!r}")
    print(f"spaces: action {env.action_space}, observation keys {list(env.observation_space)}")

    # Same seed, same episode (noise and every observation); another seed, another one.
    rng = np.random.default_rng(0)
    actions = [rng.uniform(env.action_space.low, env.action_space.high) for _ in range(30)]
    e1, e2, e3 = episode(env, 42, actions), episode(env, 42, actions), episode(env, 43, actions)
    check(all(np.array_equal(x, y) for x, y in zip(e1, e2)),
          "the same seed gave another episode")
    check(not np.array_equal(e1[0], e3[0]), "another seed gave the same initial state")
    base, _ = env.reset(options={"noise_scale": 0})
    noise = e1[0] - base["qpos"]
    check(np.max(np.abs(noise)) <= 0.1 + 1e-12 and np.all(noise != 0),
          f"initial noise {noise} (scale 0.1 around {base['qpos']})")
    # reset() without a seed goes on with the generator: another state again.
    o1, _ = env.reset(seed=5)
    o2, _ = env.reset()
    check(not np.array_equal(o1["qpos"], o2["qpos"]), "an unseeded reset repeated the state")
    print(f"seed 42 twice: {len(e1)} identical observations; seed 43 starts at {e3[0]}")

    # Hooks, truncation, and the lease released by the context manager.
    env.close()
    with UrlabEnv("arm", endpoint=rpc, frame_skip=10, max_episode_steps=50,
                  reward_fn=lambda o, a, i: -abs(o["qpos"][0] - a[0]),
                  terminated_fn=lambda o, i: o["qpos"][0] > 0.5) as env:
        env.reset(seed=0)
        steps, terminated = 0, False
        while not terminated and steps < 50:
            obs, reward, terminated, truncated, info = env.step([0.8, 0.0])
            steps += 1
            check(reward <= 0, f"reward {reward}")
        check(terminated and steps < 50, f"not terminated after {steps} steps ({obs['qpos']})")
        env.reset()
        for i in range(50):
            obs, reward, terminated, truncated, info = env.step([0.0, 0.0])
            check(truncated == (i == 49) and not terminated, f"step {i}: {terminated} {truncated}")
    with StepClient(rpc) as c:  # at once, not after the lease timeout
        check(c.info["mode"] == "live", f"mode after the env closed: {c.info['mode']}")
        c.set_mode("direct")  # the lease is free: no not_driver
        c.set_mode("live")
    print(f"terminated after {steps} steps; truncated at 50; lease released on close")

    # A vector env over two servers; next-step autoreset; a lost server replaced.
    proc2, rpc2 = server(scene)
    replaced = []

    def replace(i):
        p, endpoint = server(scene)
        replaced.append((i, p))
        return UrlabEnv("arm", endpoint=endpoint, frame_skip=20, max_episode_steps=3,
                        timeout=5.0)

    envs = UrlabVectorEnv.over_servers([rpc, rpc2], "arm", frame_skip=20, max_episode_steps=3,
                                       replace=replace, timeout=5.0)
    obs, infos = envs.reset(seed=0)
    check(obs["qpos"].shape == (2, 2) and envs.observation_space.contains(obs),
          f"batched reset obs {obs['qpos'].shape}")
    check(np.array_equal(infos["_step"], [True, True]), f"infos {infos}")
    first = obs["qpos"].copy()
    for t in range(3):
        obs, rewards, terminated, truncated, infos = envs.step(np.full((2, 2), 0.7))
        check(envs.observation_space.contains(obs), "batched step obs outside the space")
        check(list(truncated) == [t == 2] * 2 and not terminated.any(), f"step {t}: {truncated}")
    check(np.all(np.abs(obs["qpos"] - first) > 0.05), "the arms did not move")
    obs, rewards, terminated, truncated, infos = envs.step(np.full((2, 2), -0.7))
    check(np.array_equal(obs["qpos"], first) and not rewards.any() and not truncated.any(),
          f"autoreset step: qpos {obs['qpos']} (first {first}), rewards {rewards}")
    print(f"vector env: truncated at step 3, reset at step 4 to {obs['qpos'].tolist()}")

    proc2.kill()  # server 1 dies
    proc2.wait()
    obs, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 2)))
    check(list(truncated) == [False, True] and infos.get("server_lost", [0, 0])[1],
          f"a lost server: truncated {truncated}, infos {infos}")
    obs, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 2)))
    check(len(replaced) == 1 and replaced[0][0] == 1, f"replacements {replaced}")
    check(np.array_equal(obs["qpos"][1], first[1]) and not truncated[1],
          f"the replacement's first observation {obs['qpos'][1]}")
    obs, *_ = envs.step(np.full((2, 2), 0.3))
    check(envs.observation_space.contains(obs), "after the replacement")
    envs.close()
    print("a killed server: truncated, replaced, reset, stepping again")

    # Cameras in the observation (rendered from the step's own state), observation levels.
    cams = os.path.join(SOURCE, "tests", "data", "cameras", "two_cameras.yaml")
    _, rpc3 = server(cams, "--files-dir", tmp)
    with UrlabEnv("rig", endpoint=rpc3, cameras=["top", "rig/top/depth"],
                  observations="minimal") as env:
        space = env.observation_space
        check(space["cameras"]["top"].shape == (48, 64, 3) and
              space["cameras"]["rig/top/depth"].shape == (48, 64), f"camera spaces {space}")
        check(set(space) == {"qpos", "qvel", "cameras"}, f"minimal level: {list(space)}")
        obs, _ = env.reset(seed=0)
        check(space.contains(obs), "reset obs with cameras outside the space")
        obs, *_ = env.step(env.action_space.sample())
        check(space.contains(obs), "step obs with cameras outside the space")
    print("cameras: rgb and depth images in the observation space")
    stop_all()
    print("PASS")


if __name__ == "__main__":
    main()
