#!/usr/bin/env python3
"""End to end: one environment, whatever the back end. The PD arm of
examples/scenes/arm_reach.yaml (controller pd, kp 400, kv 20: actions are joint targets) stepped
side by side through every way URLab serves it:

- UrlabEnv: articulation `arm` of `urlab run SCENE` (the step server's targets, its engine's
  own controllers);
- UrlabVectorEnv.in_process: URLab's C library in this process (3 environments);
- UrlabVectorEnv.over_batch: a batched server, `urlab run SCENE --envs 3`;
- ServerPool.batch_vector_env: 2 batched servers x 2 environments on a Dask LocalCluster.

Checked:
- every back end's action space is the joints' ranges (the PD's targets), and holding the
  target 0.5 rad on both joints for 2 s gives every environment of every back end the same
  trajectory, bit for bit, ending within 0.05 rad of the target (before the scene's controllers
  ran in batched environments, the in-process arm ended at [0.579, 1.671]: 0.5 as raw torque);
- with raw_actions (`urlab run --raw-actions`) the actions are the controls, bounded by the
  ctrlranges, in process and served alike;
- the task URLab/ArmReach-v0 (-1..1 actions scaled to the targets' ranges, reset noise, seeds)
  gives the same observations, rewards and flags in process, on the batched server and on the
  Dask servers for the same seed and actions;
- two in-process batches in one process (a training and an evaluation env, and a humanoid beside
  them) step independently: the evaluation env's episode is the one it runs alone;
- a scene's keyframe sequence starts again with each episode of a batched environment.
Usage: backends_e2e.py URLAB_BINARY SOURCE_DIR LIBRARY
"""
import os
import sys
import tempfile

import numpy as np

URLAB, SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:4])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
os.environ["URLAB_BINARY"] = URLAB
os.environ["URLAB_BATCH_LIBRARY"] = LIBRARY
# Dask's worker scratch space for this run alone.
os.environ["DASK_TEMPORARY_DIRECTORY"] = tempfile.mkdtemp(prefix="urlab_dask_")
import gymnasium  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402

import urlab_client  # noqa: E402,F401  (registers the task ids)
from urlab_client import UrlabEnv, UrlabVectorEnv  # noqa: E402
from urlab_client.cluster import ServerPool  # noqa: E402
from urlab_client.tasks import TASKS  # noqa: E402
from urlab_process import PROCS, check, start_announced, stop_all  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "scenes", "arm_reach.yaml")
HUMANOID = os.path.join(SOURCE, "examples", "scenes", "humanoid_pd.yaml")
SWING = os.path.join(SOURCE, "examples", "scenes", "two_arms_swing.yaml")
FRAME_SKIP, STEPS = 10, 100  # 0.02 s per env step, 2 s
TARGET = 0.5
JOINT_RANGES = np.array([[-2.6, 2.6], [-2.4, 2.4]])  # servo_arm.xml's shoulder and elbow


def hold_batched(envs):
    """qpos of every environment after each of STEPS steps holding TARGET, from reset(seed=0)."""
    envs.reset(seed=0)
    action = np.full((envs.num_envs, 2), TARGET)
    out = []
    for _ in range(STEPS):
        obs, *_ = envs.step(action)
        out.append(np.array(obs["qpos"]))
    return np.stack(out, axis=1)  # (envs, steps, nq)


def hold_single(env):
    env.reset(seed=0)
    out = []
    for _ in range(STEPS):
        obs, *_ = env.step(np.full(2, TARGET))
        out.append(np.array(obs["qpos"]))
    return np.stack(out)[None]  # (1, steps, nq)


def check_bounds(name, space):
    check(np.array_equal(np.stack([space.low, space.high], axis=1), JOINT_RANGES),
          f"{name}: action bounds {space.low} / {space.high}, expected the joints' ranges")


def task_run(envs, actions):
    """Observations, rewards and flags of reset(seed=4) then `actions`."""
    obs, _ = envs.reset(seed=4)
    out = [(obs.copy(),)]
    for a in actions:
        obs, rewards, terminated, truncated, _ = envs.step(a)
        out.append((obs.copy(), rewards.copy(), terminated.copy(), truncated.copy()))
    return out


def same_runs(a, b, what):
    for t, (x, y) in enumerate(zip(a, b)):
        for k, (u, v) in enumerate(zip(x, y)):
            check(np.array_equal(u, v), f"{what}: step {t}, part {k} differs:\n{u}\n{v}")


def main():
    task = TASKS["ArmReach"]
    noise = ["--reset-noise", str(task.reset_noise_scale)]
    # --- The targets held: UrlabEnv and the in-process batch, then the served batches.
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--max-speed",
                                      duration=86400)
    PROCS.append(proc)
    with UrlabEnv("arm", endpoint=announced["endpoints"]["rpc"], frame_skip=FRAME_SKIP,
                  observations="minimal") as env:
        check_bounds("UrlabEnv", env.action_space)
        runs = {"UrlabEnv": hold_single(env)}
    with UrlabVectorEnv.in_process(SCENE, 3, threads=2, frame_skip=FRAME_SKIP) as envs:
        check_bounds("in_process", envs.single_action_space)
        runs["in_process"] = hold_batched(envs)
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--max-speed", "--envs", "3",
                                      "--threads", "2", duration=86400)
    PROCS.append(proc)
    with UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"], frame_skip=FRAME_SKIP) as envs:
        check_bounds("over_batch", envs.single_action_space)
        runs["over_batch"] = hold_batched(envs)

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=40) as cluster, Client(cluster) as client:
        pool = ServerPool(client, SCENE, 2, urlab=URLAB, envs_per_server=2, threads=1)
        with pool.batch_vector_env(frame_skip=FRAME_SKIP) as envs:
            check_bounds("dask", envs.single_action_space)
            runs["dask"] = hold_batched(envs)
        # The task on the Dask servers (their --reset-noise the task's).
        pool = ServerPool(client, SCENE, 2, urlab=URLAB, envs_per_server=2, threads=1,
                          args=["--no-cameras", "--max-speed"] + noise)
        rng = np.random.default_rng(9)
        actions = [rng.uniform(-1, 1, size=(4, 2)).astype(np.float32) for _ in range(30)]
        with pool.batch_vector_env(task="ArmReach") as envs:
            dask_task = task_run(envs, actions)

    reference = runs["UrlabEnv"][0]
    for name, run in runs.items():
        for i, qpos in enumerate(run):
            check(np.array_equal(qpos, reference),
                  f"{name} environment {i}: holding the targets differs from UrlabEnv; final "
                  f"qpos {qpos[-1]} vs {reference[-1]}, first difference at step "
                  f"{int(np.argmax(np.any(qpos != reference, axis=1)))}")
    final = reference[-1]
    check(np.all(np.abs(final - TARGET) < 0.05), f"the PD did not reach its targets: {final}")
    print(f"holding {TARGET} rad for 2 s: qpos {final} in every environment of "
          f"{', '.join(f'{k} ({len(v)})' for k, v in runs.items())}")

    # --- raw_actions: the controls themselves, the scene's PD off (in process and served alike).
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--max-speed", "--envs", "2",
                                      "--raw-actions", duration=86400)
    PROCS.append(proc)
    with UrlabVectorEnv.in_process(SCENE, 2, threads=1, frame_skip=FRAME_SKIP,
                                   raw_actions=True) as envs:
        check(np.array_equal(envs.single_action_space.low, [-1, -1]), "raw bounds: ctrlrange")
        raw_local = hold_batched(envs)
    with UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"], frame_skip=FRAME_SKIP) as envs:
        raw_served = hold_batched(envs)
    check(np.array_equal(raw_local, raw_served), "raw actions: in process and served differ")
    check(np.abs(raw_local[0, -1] - reference[-1]).max() > 0.1,
          f"raw controls 0.5 ended where the PD targets did: {raw_local[0, -1]}")
    print(f"raw_actions: controls 0.5 for 2 s leave qpos {raw_local[0, -1]}, in process and "
          "served alike")

    # --- The task: in process, on the batched server and on the Dask servers.
    served_proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--max-speed",
                                             "--envs", "4", "--threads", "2", *noise,
                                             duration=86400)
    PROCS.append(served_proc)
    envs = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=4,
                              vectorization_mode="vector_entry_point", threads=2)
    check_bounds("make_vec's batch", _target_space(envs))
    local = task_run(envs, actions)
    envs.close()
    with UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"], task=task) as envs:
        served = task_run(envs, actions)
    same_runs(local, served, "ArmReach in process / batched server")
    same_runs(local, dask_task, "ArmReach in process / Dask servers")
    distances = [-r[1] for r in local[1:]]
    print(f"ArmReach-v0, 30 steps x 4 environments, seed 4: in process, batched server and Dask "
          f"the same bit for bit (mean distance {np.mean(distances):.3f} m)")

    # --- Several in-process batches in one process.
    eval_actions = [np.full((2, 2), 0.3 * np.sin(t), dtype=np.float32) for t in range(20)]
    alone = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=2,
                               vectorization_mode="vector_entry_point")
    expected = task_run(alone, eval_actions)
    alone.close()
    train = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=4,
                               vectorization_mode="vector_entry_point")
    evaluate = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=2,
                                  vectorization_mode="vector_entry_point")
    humanoids = UrlabVectorEnv.in_process(HUMANOID, 2, threads=1)
    train.reset(seed=100)
    humanoids.reset(seed=1)
    obs, _ = evaluate.reset(seed=4)
    got = [(obs.copy(),)]
    for t, a in enumerate(eval_actions):
        train.step(train.action_space.sample())
        humanoids.step(humanoids.action_space.sample())
        obs, rewards, terminated, truncated, _ = evaluate.step(a)
        got.append((obs.copy(), rewards.copy(), terminated.copy(), truncated.copy()))
    same_runs(expected, got, "the evaluation batch beside a training batch and humanoids")
    for envs in (train, evaluate, humanoids):
        envs.close()
    print("three in-process batches in one process: the evaluation episode is the one it runs "
          "alone")

    # A keyframe sequence (two_arms_swing.yaml's left arm, autoplay) starts again with each
    # episode: seed 5's episode after seed 6's is the one a fresh batch runs from seed 5.
    def episode(envs, seed):
        envs.reset(seed=seed)
        return np.array([envs.step(np.zeros((1, 4)))[0]["qpos"].copy() for _ in range(80)])

    def swing():
        return UrlabVectorEnv.in_process(SWING, 1, threads=1, frame_skip=10,
                                         reset_noise_scale=0.05)
    with swing() as fresh, swing() as used:
        first = episode(fresh, 5)
        other = episode(used, 6)
        again = episode(used, 5)
    check(np.array_equal(first, again) and not np.array_equal(first, other),
          "a keyframe sequence does not restart with its episode")
    check(np.ptp(first[:, 0, 0]) > 0.5, f"the left arm did not swing: {first[::20, 0, 0]}")
    print("backends_e2e: ok")


def _target_space(envs):
    """The batch's own action bounds behind a task's -1..1 actions (the targets' ranges)."""
    from gymnasium import spaces
    backend = envs.unwrapped._backend
    mid, half = backend._ctrl_mid, backend._ctrl_half
    return spaces.Box(mid - half, mid + half, dtype=np.float64)


if __name__ == "__main__":
    try:
        main()
    finally:
        stop_all()
