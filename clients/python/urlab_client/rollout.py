"""Rollout workers on a Dask cluster: each worker holds a batch of environments inside its own
process (UrlabVectorEnv.in_process: URLab's C library, no server) and steps it with the policy it
is sent, returning whole trajectories. The driver is not in the step loop: per call it sends a
policy and gets back `steps` steps of every environment, so the workers step in parallel without
waiting for one another (Sample Factory's and RLlib's rollout workers, over Dask).

    from distributed import Client, LocalCluster
    from urlab_client.rollout import RolloutPool

    with Client(LocalCluster(n_workers=2, threads_per_worker=1)) as client:
        with RolloutPool(client, "examples/scenes/humanoid_pd.yaml", envs_per_worker=16) as pool:
            policy = lambda obs: np.zeros((len(obs["qpos"]), 21))
            for batch in pool.run(policy, steps=200):   # one per worker, in worker order
                batch["rewards"].shape                  # (200, 16)

A policy is any picklable callable obs -> actions (a dict of (envs, k) arrays in, an (envs, nu)
array out), e.g. a function closing over a torch module's state; it is sent with each call, so
an updated policy takes effect at the next one. Each worker's environments keep running from one
call to the next (gymnasium's next-step autoreset inside). reward_fn, terminated_fn and
max_episode_steps are UrlabVectorEnv's, applied on the worker.

A worker that dies loses its call: run() returns None in its place (and counts it in
`pool.lost`), and the next call starts a new rollout worker for that slot on a live worker (Dask
restarts a dead worker process). Workers need the library: found as UrlabVectorEnv.in_process
finds it (library=, $URLAB_BATCH_LIBRARY on the worker, `urlab` on the worker's PATH).
"""
import numpy as np

from urlab_client.vector import UrlabVectorEnv


class RolloutWorker:
    """A Dask actor: one in-process batch on its worker (RolloutPool makes them)."""

    def __init__(self, scene, envs, threads, seed, options):
        import distributed
        from urlab_client.cluster import _host
        # Pause the worker's statistical profiler while it steps (as a worker hosting a server).
        self._worker = distributed.get_worker()
        self.env = UrlabVectorEnv.in_process(scene, envs, threads=threads, **options)
        try:
            self.obs, _ = self.env.reset(seed=seed)
        except BaseException:
            self.env.close()
            raise
        _host(self._worker, +1)  # counted once it exists (close() uncounts it)

    def spaces(self):
        """(single_action_space, single_observation_space) of the environments."""
        return self.env.single_action_space, self.env.single_observation_space

    def rollout(self, policy, steps):
        """`steps` steps of every environment with `policy`; arrays over (steps, envs, ...),
        the observations over (steps + 1, envs, ...) (the first: where the call started)."""
        import time
        env, obs, steps = self.env, self.obs, int(steps)
        n, nu = env.num_envs, env.single_action_space.shape[0]
        observations = {k: np.empty((steps + 1,) + v.shape) for k, v in obs.items()}
        actions = np.empty((steps, n, nu))
        rewards = np.empty((steps, n))
        terminated = np.empty((steps, n), dtype=bool)
        truncated = np.empty((steps, n), dtype=bool)
        for k, v in obs.items():
            observations[k][0] = v
        batch = env.envs[0]
        stepping, cpu = 0.0, time.thread_time()
        for t in range(steps):
            a = actions[t]
            a[...] = policy(obs)
            obs, rewards[t], terminated[t], truncated[t], _ = env.step(a)
            stepping += batch._step_seconds
            for k, v in obs.items():
                observations[k][t + 1] = v
        self.obs = obs
        return {"obs": observations, "actions": actions, "rewards": rewards,
                "terminated": terminated, "truncated": truncated, "env_steps": steps * n,
                "step_seconds": stepping, "cpu_seconds": time.thread_time() - cpu}

    def close(self):
        from urlab_client.cluster import _host
        if self.env is not None:
            self.env.close()
            self.env = None
            _host(self._worker, -1)


class RolloutPool:
    """One RolloutWorker per worker of `client`'s cluster (or on n_workers of them),
    each with envs_per_worker environments of `scene` on `threads` threads. Worker k's
    environments start with seeds seed + k * envs_per_worker + i."""

    def __init__(self, client, scene, envs_per_worker=16, threads=1, seed=0, n_workers=None,
                 **options):
        import os
        self.client = client
        self.scene = os.path.abspath(scene)
        self.envs_per_worker = int(envs_per_worker)
        self.threads = int(threads)
        self.seed = int(seed)
        self.options = options
        live = sorted(client.scheduler_info()["workers"])
        if not live:
            raise RuntimeError("the Dask cluster has no worker")
        self.n = int(n_workers) if n_workers is not None else len(live)
        if self.n > len(live):
            raise ValueError(f"{self.n} rollout workers for {len(live)} Dask workers (one "
                             "in-process batch per worker process: its threads are that "
                             "worker's cores)")
        self.workers = live[:self.n]  # each slot's worker
        self.lost = 0
        self.actors = [None] * self.n
        try:
            for k in range(self.n):
                self._start(k)
            self.single_action_space, self.single_observation_space = \
                self.actors[0].spaces().result()
        except BaseException:
            self.close()
            raise
        self.nu = self.single_action_space.shape[0]

    def _start(self, k):
        """Starts slot k's rollout worker on a live worker hosting none (one in-process batch
        per worker process, so that batches do not share cores): its own worker when it is alive, else another. Raises RuntimeError when
        every live worker hosts one already (a dead worker not restarted yet)."""
        live = sorted(self.client.scheduler_info()["workers"])
        taken = {getattr(a, "_address", None) for a in self.actors if a is not None}
        free = [w for w in live if w not in taken]
        if not free:
            raise RuntimeError(f"rollout slot {k}: no live worker without a rollout worker")
        where = self.workers[k] if self.workers[k] in free else free[0]
        future = self.client.submit(RolloutWorker, self.scene, self.envs_per_worker, self.threads,
                                    self.seed + k * self.envs_per_worker, self.options,
                                    actor=True, pure=False, workers=[where],
                                    allow_other_workers=False)
        self.actors[k] = future.result()
        self.workers[k] = where

    def run(self, policy, steps):
        """`steps` steps of every worker's environments with `policy`, the workers in parallel;
        one dict per worker (RolloutWorker.rollout's), None for a worker lost meanwhile."""
        calls = []
        for k in range(self.n):
            try:
                if self.actors[k] is None:
                    self._start(k)
                calls.append(self.actors[k].rollout(policy, steps))
            except Exception:  # noqa: BLE001 - its worker is gone: that slot starts again later
                self.actors[k] = None
                self.lost += 1
                calls.append(None)
        out = []
        for k, call in enumerate(calls):
            if call is None:
                out.append(None)
                continue
            try:
                out.append(call.result())
            except Exception:  # noqa: BLE001 - the worker died during the call
                self.actors[k] = None
                self.lost += 1
                out.append(None)
        return out

    def close(self):
        for k, actor in enumerate(self.actors):
            if actor is None:
                continue
            try:
                actor.close().result(timeout=30)
            except Exception:  # noqa: BLE001 - a worker already gone
                pass
            self.actors[k] = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


__all__ = ["RolloutPool", "RolloutWorker"]
