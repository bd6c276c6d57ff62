#!/usr/bin/python3
"""End to end: UrlabVectorEnv over batched servers (`urlab run SCENE --envs N`), real processes:

- over ZeroMQ and over the shared-memory channel: spaces from batch_info (actions are the
  actuators' ctrlrange; the observation {qpos, qvel, sensordata} of the whole model), and the
  observations inside them;
- seeds: environment i of an 8-environment run reset with seed s + i runs the same episode, bit
  for bit, as the only environment of a 1-environment run reset with seed s + i and given the
  same actions (environment 0, the engine's own simulation, and a batch environment alike);
- gymnasium's next-step autoreset: max_episode_steps truncates every environment, and the next
  step resets them (actions ignored, reward 0, no flags, time 0);
- reset_mask resets only those environments;
- two batched servers as one vector env (2 x 4 environments).
Usage: batch_env_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import sys
import tempfile

import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import UrlabVectorEnv  # noqa: E402
from urlab_process import PROCS, arm_scene, check, start_announced, stop_all  # noqa: E402
from urlab_process import wave_actions as actions_for  # noqa: E402

NOISE = "0.05"


def server(scene, envs, *extra):
    proc, a = start_announced(URLAB, scene, "--no-cameras", "--max-speed", "--envs", str(envs),
                              "--reset-noise", NOISE, *extra, duration=86400)
    PROCS.append(proc)
    return a["endpoints"]["rpc"]


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_batch_")
    scene = arm_scene(tmp, "arm.yaml", controller=False)
    rpc8 = server(scene, 8, "--threads", "2")
    rpc1 = server(scene, 1)

    for shm in (False, True):
        envs = UrlabVectorEnv.over_batch(rpc8, shared_memory=shm, max_episode_steps=5)
        transport = envs.envs[0].client.transport
        check(transport == ("shm" if shm else "zmq"), f"transport {transport}, shm={shm}")
        check(envs.num_envs == 8, f"num_envs {envs.num_envs}")
        check(envs.single_action_space.shape == (2,) and
              np.all(envs.single_action_space.low == -1) and
              np.all(envs.single_action_space.high == 1),
              f"action space {envs.single_action_space}")
        obs, infos = envs.reset(seed=10)
        check(set(obs) == {"qpos", "qvel", "sensordata"}, f"keys {list(obs)}")
        check(obs["qpos"].shape == (8, 2), f"qpos {obs['qpos'].shape}")
        check(envs.observation_space.contains(obs), "reset obs outside the observation space")
        check(np.all(infos["time"] == 0), f"reset time {infos['time']}")
        check(len({tuple(q) for q in obs["qpos"]}) == 8, "the seeds did not give 8 starts")
        path = [np.concatenate([obs["qpos"], obs["qvel"]], axis=1).copy()]
        for t in range(5):
            obs, rewards, terminated, truncated, infos = envs.step(actions_for(t, 8, 2))
            check(envs.observation_space.contains(obs), "step obs outside the observation space")
            path.append(np.concatenate([obs["qpos"], obs["qvel"]], axis=1).copy())
            check(not terminated.any(), "terminated without a terminated_fn")
            check(truncated.all() == (t == 4) and truncated.any() == (t == 4),
                  f"step {t}: truncated {truncated}")
        check(np.allclose(infos["time"], 5 * 0.002), f"time after 5 steps {infos['time']}")
        # Next-step autoreset: every environment resets, its action ignored.
        obs, rewards, terminated, truncated, infos = envs.step(np.full((8, 2), 1.0))
        check(not terminated.any() and not truncated.any() and not rewards.any(),
              f"the autoreset step ended episodes: {terminated} {truncated} {rewards}")
        check(np.all(infos["time"] == 0), f"autoreset time {infos['time']}")
        # reset_mask: only environments 2 and 5.
        obs, *_ = envs.step(np.zeros((8, 2)))
        mask = np.zeros(8, dtype=bool)
        mask[[2, 5]] = True
        before = obs["qpos"].copy()
        obs, infos = envs.reset(seed=10, options={"reset_mask": mask})
        check(np.all(infos["time"][mask] == 0), f"masked reset times {infos['time']}")
        check(np.array_equal(obs["qpos"][2], path[0][2, :2]),
              "environment 2 reset with seed 12 does not start where it did")
        check(np.array_equal(obs["qpos"][0], before[0]), "environment 0 was reset too")
        envs.close()

        # The same seeds on a 1-environment server: environment i's episode, bit for bit.
        for i in (0, 3, 7):
            single = UrlabVectorEnv.over_batch(rpc1, shared_memory=shm)
            o, _ = single.reset(seed=10 + i)
            got = [np.concatenate([o["qpos"], o["qvel"]], axis=1)[0].copy()]
            for t in range(5):
                o, *_ = single.step(actions_for(t, 8, 2)[i:i + 1])
                got.append(np.concatenate([o["qpos"], o["qvel"]], axis=1)[0].copy())
            single.close()
            for t, row in enumerate(got):
                check(np.array_equal(row, path[t][i]),
                      f"environment {i}, step {t}: {path[t][i]} in the batch, {row} alone")

    # Two batched servers as one vector env: environments 0-3 and 4-7.
    rpc4a = server(scene, 4)
    rpc4b = server(scene, 4)
    envs = UrlabVectorEnv.over_batch([rpc4a, rpc4b])
    check(envs.num_envs == 8, f"two servers: num_envs {envs.num_envs}")
    obs, _ = envs.reset(seed=10)
    check(np.array_equal(obs["qpos"], path[0][:, :2]),
          "two servers of 4 with seed 10 do not start as one server of 8")
    for t in range(5):
        obs, *_ = envs.step(actions_for(t, 8, 2))
    check(np.array_equal(np.concatenate([obs["qpos"], obs["qvel"]], axis=1), path[5]),
          "two servers of 4 do not run the 8 episodes of one server of 8")
    envs.close()

    stop_all()
    print("batch_env_e2e: ok")


if __name__ == "__main__":
    main()
