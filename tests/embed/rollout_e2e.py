#!/usr/bin/python3
"""End to end: Dask rollout workers (urlab_client.rollout) on a LocalCluster of 2 worker
processes, each stepping 4 environments of the humanoid scene inside its own process:

- shapes: observations (steps + 1, envs, k), actions, rewards, flags (steps, envs); the
  environments go on from one call to the next (the next call's first observation is the last
  one of the previous call);
- the same seed gives the same rollouts (a second pool), another seed others; the policy is
  sent with each call (a new one takes effect at once) and reward_fn runs on the worker;
- a worker process killed (SIGKILL) loses its call (None, pool.lost), and the next call starts
  its rollout worker again on a live worker.
Usage: rollout_e2e.py SOURCE_DIR LIBRARY
"""
import os
import signal
import sys
import tempfile
import time

import numpy as np

SOURCE, LIBRARY = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
os.environ["DASK_TEMPORARY_DIRECTORY"] = tempfile.mkdtemp(prefix="urlab_dask_")
from distributed import Client, LocalCluster  # noqa: E402

from urlab_client.rollout import RolloutPool  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "scenes", "humanoid_pd.yaml")
ENVS, STEPS = 4, 15


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


def height(obs, actions, infos):
    return obs["qpos"][:, 2]  # the torso's height: a reward the worker computes


def waves(obs):
    """A deterministic policy of the observation (picklable: a module function)."""
    return np.tanh(np.outer(obs["qpos"][:, 2], np.linspace(-1, 1, 21)))


def main():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=40) as c, Client(c) as client:
        pids = client.run(os.getpid)  # {worker address: pid}
        options = dict(library=LIBRARY, reset_noise_scale=0.05, reward_fn=height)
        with RolloutPool(client, SCENE, envs_per_worker=ENVS, seed=3, **options) as pool:
            if pool.n != 2 or pool.nu != 21:
                fail(f"{pool.n} workers, nu {pool.nu}")
            first = pool.run(waves, STEPS)
            for k, r in enumerate(first):
                if r is None:
                    fail(f"worker {k} returned nothing")
                if r["obs"]["qpos"].shape != (STEPS + 1, ENVS, 28) or \
                        r["actions"].shape != (STEPS, ENVS, 21) or \
                        r["rewards"].shape != (STEPS, ENVS) or r["truncated"].shape != (STEPS, ENVS):
                    fail(f"worker {k}: shapes {r['obs']['qpos'].shape} {r['actions'].shape}")
                if not np.array_equal(r["rewards"], r["obs"]["qpos"][1:, :, 2]):
                    fail(f"worker {k}: the rewards are not reward_fn's")
            if np.array_equal(first[0]["obs"]["qpos"][0], first[1]["obs"]["qpos"][0]):
                fail("the two workers' environments started alike (seeds 3.. and 7..)")
            second = pool.run(lambda obs: np.zeros((len(obs["qpos"]), 21)), STEPS)
            for k in range(2):
                if not np.array_equal(second[k]["obs"]["qpos"][0], first[k]["obs"]["qpos"][-1]):
                    fail(f"worker {k}: the second call did not go on from the first")
                if np.any(second[k]["actions"]):
                    fail(f"worker {k}: the new policy did not take effect")
        with RolloutPool(client, SCENE, envs_per_worker=ENVS, seed=3, **options) as again:
            same = again.run(waves, STEPS)
            for k in range(2):
                if not np.array_equal(same[k]["obs"]["qpos"], first[k]["obs"]["qpos"]):
                    fail(f"worker {k}: the same seed gave another rollout")
        with RolloutPool(client, SCENE, envs_per_worker=ENVS, seed=4, **options) as other:
            if np.array_equal(other.run(waves, 1)[0]["obs"]["qpos"][0],
                              first[0]["obs"]["qpos"][0]):
                fail("another seed gave the same start")

        with RolloutPool(client, SCENE, envs_per_worker=ENVS, **options) as pool:
            pool.run(waves, 2)
            victim = pool.workers[1]
            os.kill(pids[victim], signal.SIGKILL)
            t0 = time.monotonic()
            got = pool.run(waves, 200)
            if got[1] is not None or pool.lost != 1 or got[0] is None:
                fail(f"killed {victim}: results {[g is None for g in got]}, lost {pool.lost}")
            back = None
            while time.monotonic() - t0 < 120:
                back = pool.run(waves, STEPS)
                if all(r is not None for r in back):
                    break
            if back is None or any(r is None for r in back):
                fail(f"the killed worker's slot did not come back (lost {pool.lost})")
            print(f"killed {victim}: its call lost, its slot back after "
                  f"{time.monotonic() - t0:.1f} s ({pool.lost} call(s) lost)")
    print("PASS")


if __name__ == "__main__":
    main()
