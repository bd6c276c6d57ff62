#!/usr/bin/python3
"""End to end: batched URLab servers (`urlab run --envs 4`) on a Dask LocalCluster (2 worker
processes, each with a nanny) and one vector env over every environment of them
(urlab_client.cluster.ServerPool(..., envs_per_server=4).batch_vector_env()).

- 2 servers x 4 environments, one server per worker, stepped as one vector env of 8; started
  without `threads`, each steps on its share of this machine's cores (both servers are here:
  the cores over 2, at least 1; `urlab run --envs` alone would take every core);
- a worker process killed (SIGKILL) takes its server with it: that server's 4 environments end
  truncated (infos["server_lost"]), the scheduler runs the server again, and they come back on
  the replacement at their autoreset while the other 4 go on;
- closing the vector env stops the servers (the tasks finish).
Usage: cluster_batch_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import signal
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
# Dask's worker scratch space (its folders and their lock files) for this run alone: test runs
# sharing the machine never lock or purge each other's.
os.environ["DASK_TEMPORARY_DIRECTORY"] = tempfile.mkdtemp(prefix="urlab_dask_")
from distributed import Client, LocalCluster  # noqa: E402

from urlab_client.cluster import ServerPool, server_threads  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


def main():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=40) as c, Client(c) as client:
        before = client.run(os.getpid)  # {worker address: pid}
        pool = ServerPool(client, SCENE, 2, urlab=URLAB, envs_per_server=4)
        announced = [pool.announced(i) for i in range(2)]
        if len({a["worker"] for a in announced}) != 2:
            fail(f"servers not spread over both workers: {announced}")
        envs = pool.batch_vector_env(timeout=3.0, max_episode_steps=50)
        if envs.num_envs != 8:
            fail(f"num_envs {envs.num_envs}")
        share = server_threads(len(os.sched_getaffinity(0)), 2)
        threads = [c.info["threads"] for c in envs.envs]
        if threads != [min(share, 4)] * 2:
            fail(f"stepping threads per server {threads}, expected {min(share, 4)} each "
                 f"({len(os.sched_getaffinity(0))} cores, 2 servers)")
        for cores, servers, expected in ((2, 2, 1), (2, 1, 2), (16, 3, 5), (1, 4, 1), (8, 0, 8)):
            if server_threads(cores, servers) != expected:
                fail(f"server_threads({cores}, {servers}) = {server_threads(cores, servers)}")
        obs, infos = envs.reset(seed=0)
        if obs["qpos"].shape != (8, 2) or not envs.observation_space.contains(obs):
            fail(f"batched obs {obs['qpos'].shape}")
        for _ in range(10):
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
        victim = announced[1]["worker"]
        os.kill(before[victim], signal.SIGKILL)
        seen_lost, back, t0 = set(), False, time.monotonic()
        while time.monotonic() - t0 < 120:
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
            if "server_lost" in infos:
                lost = {i for i in range(8) if infos["server_lost"][i]}
                seen_lost |= lost
                if not all(truncated[i] for i in lost):
                    fail(f"a lost server's episodes not truncated: {truncated}")
            if seen_lost == set(range(4, 8)):
                if envs.envs[1].server_session != announced[1]["session"] and \
                        "server_lost" not in infos:
                    back = True
                    break
        if seen_lost != set(range(4, 8)) or not back:
            fail(f"killed worker {victim}: lost {sorted(seen_lost)} (expected 4..7), "
                 f"replaced {back}")
        for _ in range(10):
            obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
            if "server_lost" in infos:
                fail(f"servers still lost after the replacement: {infos}")
        if not envs.observation_space.contains(obs):
            fail("observation after the replacement outside the space")
        print(f"killed {victim}: environments 4..7 truncated, then back on "
              f"{envs.envs[1].endpoint}, {time.monotonic() - t0:.1f} s")
        envs.close()
        states = {f.status for f in pool.futures}
        if states != {"finished"}:
            fail(f"server tasks after close: {states}")
    print("PASS")


if __name__ == "__main__":
    main()
