#!/usr/bin/python3
"""End to end: asynchronous stepping of UrlabVectorEnv over batched servers (EnvPool's send/recv,
gymnasium's step_async/step_wait), real `urlab run --envs N` processes:

- send/recv pipelined over two servers of 4 environments (one server steps while the client
  handles the other's reply) gives every environment the trajectory step() gives it: the same
  observations bit for bit, rewards, flags, and the same next-step autoreset
  (max_episode_steps truncates, the next step resets);
- recv() gives one server's environments at a time, in the order sent, infos["env_id"] their
  indices; step_async + step_wait is step();
- misuse is refused with a clear error: a second send() to a server before its recv(), step()
  or reset() while a send() waits, recv() with nothing sent, env_id that is not whole servers';
- close() with sends in flight leaves the servers usable (the next vector env takes over).
Usage: batch_async_e2e.py URLAB_BINARY SOURCE_DIR
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

STEPS = 12
EPISODE = 5  # max_episode_steps: truncations at steps 4 and 10, resets at 5 and 11


def server(scene, envs):
    proc, a = start_announced(URLAB, scene, "--no-cameras", "--max-speed", "--envs", str(envs),
                              "--threads", "1", "--reset-noise", "0.05", duration=86400)
    PROCS.append(proc)
    return a["endpoints"]["rpc"]


def reward_fn(obs, actions, infos):
    return obs["qpos"][:, 0] - 0.1 * actions[:, 0]


def expect_error(kind, fn, what):
    try:
        fn()
    except kind:
        return
    except Exception as e:  # noqa: BLE001
        check(False, f"{what}: {type(e).__name__} {e}, expected {kind.__name__}")
    check(False, f"{what}: no error, expected {kind.__name__}")


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_batch_async_")
    scene = arm_scene(tmp, "arm.yaml", controller=False)
    rpcs = [server(scene, 4), server(scene, 4)]

    def make(shared_memory=True):
        return UrlabVectorEnv.over_batch(rpcs, max_episode_steps=EPISODE, reward_fn=reward_fn,
                                         shared_memory=shared_memory)

    # The synchronous reference.
    envs = make()
    obs, _ = envs.reset(seed=3)
    ref = [(np.concatenate([obs["qpos"], obs["qvel"]], axis=1).copy(), None, None, None)]
    for t in range(STEPS):
        obs, rewards, terminated, truncated, infos = envs.step(actions_for(t, 8, 2))
        ref.append((np.concatenate([obs["qpos"], obs["qvel"]], axis=1).copy(), rewards.copy(),
                    terminated.copy(), truncated.copy()))
    check(ref[EPISODE][3].all() and ref[EPISODE + 1][3].sum() == 0 and
          np.all(ref[EPISODE + 1][1] == 0), "the reference run did not truncate and autoreset")
    envs.close()

    # Pipelined send/recv: server 0's step t+1 is sent before server 1's step t is received.
    envs = make()
    obs, _ = envs.reset(seed=3)
    check(np.array_equal(np.concatenate([obs["qpos"], obs["qvel"]], axis=1), ref[0][0]),
          "the reset differs")
    halves = [np.arange(0, 4), np.arange(4, 8)]
    next_t = [0, 0]
    for k in (0, 1):
        envs.send(actions_for(0, 8, 2)[halves[k]], halves[k])
    expect_error(RuntimeError, lambda: envs.send(np.zeros((4, 2)), halves[0]),
                 "a second send to a server in flight")
    expect_error(RuntimeError, lambda: envs.step(np.zeros((8, 2))), "step() with sends in flight")
    expect_error(RuntimeError, lambda: envs.reset(seed=1), "reset() with sends in flight")
    received = 0
    while received < 2 * STEPS:
        obs, rewards, terminated, truncated, infos = envs.recv()
        ids = infos["env_id"]
        k = 0 if ids[0] == 0 else 1
        check(np.array_equal(ids, halves[k]), f"recv gave env_id {ids}")
        check(k == received % 2, f"recv {received} came from server {k}: not the order sent")
        t = next_t[k]
        want_obs, want_rew, want_term, want_trunc = ref[t + 1]
        got = np.concatenate([obs["qpos"], obs["qvel"]], axis=1)
        check(np.array_equal(got, want_obs[ids]), f"server {k}, step {t}: observations differ")
        check(np.array_equal(rewards, want_rew[ids]), f"server {k}, step {t}: rewards differ")
        check(np.array_equal(terminated, want_term[ids]) and
              np.array_equal(truncated, want_trunc[ids]), f"server {k}, step {t}: flags differ")
        received += 1
        next_t[k] = t + 1
        if t + 1 < STEPS:
            envs.send(actions_for(t + 1, 8, 2)[ids], ids)
    expect_error(RuntimeError, envs.recv, "recv() with nothing sent")
    expect_error(ValueError, lambda: envs.send(np.zeros((2, 2)), [0, 1]), "half a server")
    expect_error(ValueError, lambda: envs.send(np.zeros((4, 2)), [4, 5, 6, 8]), "no env 8")
    expect_error(ValueError, lambda: envs.send(np.zeros((3, 2)), halves[1]), "actions' shape")

    # step_async + step_wait is step(), over shared memory and over ZeroMQ.
    envs.close()
    for shm in (True, False):
        envs = make(shared_memory=shm)
        check(envs.envs[0].client.transport == ("shm" if shm else "zmq"), f"transport, shm={shm}")
        obs, _ = envs.reset(seed=3)
        for t in range(STEPS):
            envs.step_async(actions_for(t, 8, 2))
            obs, rewards, terminated, truncated, infos = envs.step_wait()
            want_obs, want_rew, want_term, want_trunc = ref[t + 1]
            check(np.array_equal(np.concatenate([obs["qpos"], obs["qvel"]], axis=1), want_obs)
                  and np.array_equal(rewards, want_rew) and np.array_equal(terminated, want_term)
                  and np.array_equal(truncated, want_trunc),
                  f"step_async/step_wait (shm={shm}), step {t} differs")
            check(infos["time"].shape == (8,) and infos["_time"].all() and "env_id" not in infos,
                  f"step_wait infos {sorted(infos)}")
        if shm:
            envs.close()
    # close() with sends in flight (over ZeroMQ here) takes their replies before saying bye: the
    # servers stay usable, and the next vector env gets their leases at once.
    envs.send(actions_for(0, 8, 2))
    envs.close()
    envs = make()
    obs, _ = envs.reset(seed=3)
    check(np.array_equal(np.concatenate([obs["qpos"], obs["qvel"]], axis=1), ref[0][0]),
          "after a close with sends in flight, the reset differs")
    obs, *_ = envs.step(actions_for(0, 8, 2))
    check(np.array_equal(np.concatenate([obs["qpos"], obs["qvel"]], axis=1), ref[1][0]),
          "after a close with sends in flight, the first step differs")
    envs.close()

    stop_all()
    print("batch_async_e2e: ok")


if __name__ == "__main__":
    main()
