#!/usr/bin/python3
"""End to end: URLab servers on a Dask LocalCluster (2 worker processes, each with a nanny) and
a vector env over them (urlab_client.cluster).

- ServerPool starts 2 servers per worker (round robin), gathers their announced endpoints
  (every server on another port, each with its own session), and the vector env steps them all;
- a worker process killed (SIGKILL) takes its servers with it; the vector env ends their
  episodes as truncated (infos["server_lost"]), the nanny restarts the worker, the scheduler runs
  the lost servers again, and the vector env reconnects them at their autoreset and goes on;
- closing the vector env stops every server (the tasks finish).

`--measure K` instead prints aggregate environment steps per second of K servers on one worker
against 2K servers on two workers (the same process, one after the other).
Usage: cluster_e2e.py URLAB_BINARY SOURCE_DIR [--measure K]
"""
import os
import signal
import sys
import tempfile
import time

import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
# Dask's worker scratch space (its folders and their lock files) for this run alone: test runs
# sharing the machine never lock or purge each other's.
os.environ["DASK_TEMPORARY_DIRECTORY"] = tempfile.mkdtemp(prefix="urlab_dask_")
from distributed import Client, LocalCluster  # noqa: E402

from urlab_client.cluster import ServerPool  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


def cluster(workers):
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=40)


def steps_per_second(workers, per_worker, seconds=5.0):
    with cluster(workers) as c, Client(c) as client:
        pool = ServerPool(client, SCENE, workers * per_worker, urlab=URLAB)
        with pool.vector_env("servo_arm", frame_skip=1) as envs:
            envs.reset(seed=0)
            actions = np.zeros(envs.action_space.shape)
            for _ in range(20):
                envs.step(actions)  # warm up
            n, t0 = 0, time.monotonic()
            while time.monotonic() - t0 < seconds:
                envs.step(actions)
                n += envs.num_envs
            return n / (time.monotonic() - t0)


def measure(k, rounds=2):
    """Alternates the two configurations (the machine is shared and noisy); per-round ratios."""
    for r in range(rounds):
        one = steps_per_second(1, k)
        two = steps_per_second(2, k)
        print(f"round {r}: 1 worker x {k} servers: {one:.0f} env steps/s; 2 workers x {k}: "
              f"{two:.0f} env steps/s; ratio {two / one:.2f} (cores here: {os.cpu_count()})",
              flush=True)


def main():
    with cluster(2) as c, Client(c) as client:
        before = client.run(os.getpid)  # {worker address: pid}
        pool = ServerPool(client, SCENE, 4, urlab=URLAB)
        announced = [pool.announced(i) for i in range(4)]
        ports = {a["endpoints"]["rpc"] for a in announced}
        sessions = {a["session"] for a in announced}
        if len(ports) != 4 or len(sessions) != 4:
            fail(f"4 servers share endpoints or sessions: {ports} {sessions}")
        placed = sorted(a["worker"] for a in announced)
        if len(set(placed)) != 2:
            fail(f"servers not spread over both workers: {placed}")
        envs = pool.vector_env("servo_arm", frame_skip=5, timeout=3.0)
        obs, infos = envs.reset(seed=0)
        if obs["qpos"].shape != (4, 2) or not envs.observation_space.contains(obs):
            fail(f"batched obs {obs['qpos'].shape}")
        for _ in range(10):
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
        print(f"4 servers on {sorted(set(placed))}: stepping")

        victim = announced[0]["worker"]
        lost = [i for i, a in enumerate(announced) if a["worker"] == victim]
        os.kill(before[victim], signal.SIGKILL)
        seen_lost, back, t0 = set(), False, time.monotonic()
        while time.monotonic() - t0 < 120:
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
            if "server_lost" in infos:
                seen_lost |= {i for i in range(4) if infos["_server_lost"][i]}
                if not all(truncated[i] for i in range(4) if infos["_server_lost"][i]):
                    fail(f"a lost server's episode not truncated: {truncated}")
            if seen_lost >= set(lost):
                sessions_now = {e.server_session for e in envs.envs}
                if not sessions_now & {announced[i]["session"] for i in lost}:
                    back = True
                    break
        if seen_lost != set(lost) or not back:
            fail(f"killed worker {victim}: lost {sorted(seen_lost)} (expected {lost}), "
                 f"replaced {back}")
        for _ in range(10):
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
            if "server_lost" in infos:
                fail(f"servers still lost after the replacement: {infos}")
        if not envs.observation_space.contains(obs):
            fail("observation after the replacement outside the space")
        workers = client.scheduler_info()["workers"]
        print(f"killed {victim} (pid {before[victim]}): envs {lost} truncated, then back on "
              f"{[envs.envs[i].endpoint for i in lost]}; {len(workers)} workers now, "
              f"{time.monotonic() - t0:.1f} s")
        envs.close()  # stops the servers
        states = {f.status for f in pool.futures}
        if states != {"finished"}:
            fail(f"server tasks after close: {states}")
    print("PASS")


if __name__ == "__main__":
    if len(sys.argv) > 4 and sys.argv[3] == "--measure":
        measure(int(sys.argv[4]))
    else:
        main()
