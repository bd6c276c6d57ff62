"""UrlabVectorEnv: many environments stepped together, numpy-batched: a
gymnasium.vector.VectorEnv.

    from urlab_client import UrlabVectorEnv
    envs = UrlabVectorEnv.over_servers(["tcp://127.0.0.1:41001", "tcp://127.0.0.1:41002"], "arm")
    obs, infos = envs.reset(seed=0)                  # obs["qpos"].shape == (2, nq)
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
    envs.close()

- step() sends every sub-environment's request first, then gathers the replies, so N servers
  (N processes, on one machine or many) step in parallel.
- Autoreset is gymnasium's default, next-step (metadata["autoreset_mode"] is
  gymnasium.vector.AutoresetMode.NEXT_STEP): the step after a
  sub-environment's episode ended ignores its action, resets it (unseeded, no options) and
  returns its first observation with reward 0 and terminated = truncated = False.
- infos: {key: array over envs, "_key": bool mask of the envs that gave it}.
- A server that stops answering (its process or machine died) ends its episode as truncated
  (infos["server_lost"]); with a `replace(i)` callback (urlab_client.cluster gives one) the
  sub-environment comes back, connected to a replacement server, at its autoreset.

- Over batched servers, stepping can be asynchronous (EnvPool's send/recv): send(actions,
  env_id) sends a step for whole servers' environments and returns; recv() returns one server's
  reply (oldest first) with infos["env_id"]; step_async/step_wait are step() in two halves.
  Each environment's trajectory is the one step() gives it; the servers step while Python works:

      envs = UrlabVectorEnv.over_batch([endpoint_a, endpoint_b])   # two servers of N/2
      envs.reset(seed=0)
      envs.send(actions)                                           # every environment
      while training:
          obs, rewards, terminated, truncated, infos = envs.recv()  # one server's half
          envs.send(policy(obs), infos["env_id"])                   # the other half steps now

Backends: `_ServerBackend` drives one UrlabEnv per server (`over_servers`).
`urlab_client.batch.BatchBackend` drives batched servers (`over_batch`: `urlab run --envs N`,
many environments in one process, one request per server per step, numpy arrays in and out
without a loop over environments; the same autoreset, done by the server in the same request).
"""
from collections import OrderedDict

import numpy as np
import zmq

import gymnasium
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from urlab_client.env import UrlabEnv
from urlab_client.step import UrlabError

NEXT_STEP = AutoresetMode.NEXT_STEP

# What a lost server looks like to a client: no reply in time, or a socket that cannot go on.
LOST = (TimeoutError, zmq.ZMQError, ConnectionError)  # ConnectionError: shm.ShmError


def _stack(values):
    """A list of observations (dicts of arrays) as one dict of arrays with a leading env axis."""
    first = values[0]
    if isinstance(first, dict):
        return OrderedDict((k, _stack([v[k] for v in values])) for k in first)
    return np.stack([np.asarray(v) for v in values])


def _batch_infos(infos):
    out = {}
    n = len(infos)
    for i, info in enumerate(infos):
        for key, value in info.items():
            if key not in out:
                dtype = type(value) if isinstance(value, (bool, int, float)) else object
                out[key] = np.zeros(n, dtype=dtype)
                out["_" + key] = np.zeros(n, dtype=bool)
            out[key][i] = value
            out["_" + key][i] = True
    return out


class _ServerBackend:
    """One UrlabEnv (one step server) per sub-environment."""

    def __init__(self, envs, replace=None):
        self.envs = list(envs)
        self.replace = replace

    def __len__(self):
        return len(self.envs)

    def renew(self, i):
        """Connects sub-environment i to a replacement server (replace(i) makes its env)."""
        old = self.envs[i]
        try:
            old.client._socket.close(0)  # no bye: the server is gone
        except Exception:  # noqa: BLE001
            pass
        old.client = None
        self.envs[i] = self.replace(i)

    def close(self):
        for env in self.envs:
            env.close()


class UrlabVectorEnv(VectorEnv):
    """num_envs sub-environments with identical spaces (see the module's docstring)."""

    metadata = {"autoreset_mode": NEXT_STEP, "render_modes": []}
    render_mode = None

    def __init__(self, envs=None, replace=None, on_close=None, backend=None):
        """envs: UrlabEnv instances (one per server). replace(i): a new UrlabEnv for
        sub-environment i when its server was lost (None: a lost server raises). on_close: called
        once by close() after the envs (a cluster's shutdown). backend: a batched backend
        instead of envs (see over_batch)."""
        self._on_close = on_close
        self.closed = False
        if backend is not None:  # batched servers: the backend does reset and step whole
            self._backend = backend
            self.num_envs = len(backend)
            self.single_observation_space = backend.single_observation_space
            self.single_action_space = backend.single_action_space
            self.observation_space = batch_space(self.single_observation_space, self.num_envs)
            self.action_space = batch_space(self.single_action_space, self.num_envs)
            return
        self._backend = _ServerBackend(envs, replace)
        self.num_envs = len(self._backend)
        if self.num_envs == 0:
            raise ValueError("UrlabVectorEnv needs at least one environment")
        first = self._backend.envs[0]
        for i, env in enumerate(self._backend.envs[1:], 1):
            if env.action_space.shape != first.action_space.shape or \
                    env.observation_space != first.observation_space:
                raise ValueError(f"environment {i} has other spaces than environment 0")
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, self.num_envs)
        self.action_space = batch_space(first.action_space, self.num_envs)
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._last_obs = [None] * self.num_envs

    @classmethod
    def over_servers(cls, endpoints, articulation, replace=None, on_close=None, **env_options):
        """A vector env of one UrlabEnv per step-server endpoint (UrlabEnv's options apply to
        each; `require` may be a list, one per endpoint)."""
        require = env_options.pop("require", None)
        envs = []
        try:
            for i, endpoint in enumerate(endpoints):
                r = require[i] if isinstance(require, (list, tuple)) else require
                envs.append(UrlabEnv(articulation, endpoint=endpoint, require=r, **env_options))
        except BaseException:
            for env in envs:
                env.close()
            raise
        return cls(envs, replace=replace, on_close=on_close)

    @classmethod
    def over_batch(cls, endpoints, replace=None, on_close=None, **options):
        """A vector env over every environment of one batched server (`urlab run SCENE --envs
        N`), or of several (a list of endpoints: N servers x M environments, in order).
        options: BatchBackend.connect's (require, frame_skip, reward_fn, terminated_fn,
        max_episode_steps, task; StepClient's timeout, shared_memory, ...); replace(k): a new
        urlab_client.batch.BatchClient for server k when it was lost."""
        from urlab_client.batch import BatchBackend
        backend = BatchBackend.connect(endpoints, replace=replace, **options)
        return cls(backend=backend, on_close=on_close)

    @classmethod
    def in_process(cls, scene, num_envs, threads=0, seed=None, on_close=None, **options):
        """A vector env over `num_envs` environments of `scene` stepped inside this process
        (urlab_client.inproc: URLab's C library, no server). threads: stepping threads (0: the
        cores); seed: environment i starts with seed + i (None: the scene's). options:
        frame_skip, reward_fn, terminated_fn, max_episode_steps (vector steps, truncation),
        server_max_episode_steps (physics steps, as `urlab run --max-episode-steps`),
        reset_noise_scale, task (urlab_client.tasks), library, log_level, raw_actions (the
        actions are the controls, the scene's controllers off; by default every environment
        runs them, so a PD scene takes joint targets). The old names
        n_steps and reset_noise still work, with a FutureWarning."""
        from urlab_client.inproc import in_process_backend
        backend = in_process_backend(scene, num_envs, threads=threads, seed=seed, **options)
        return cls(backend=backend, on_close=on_close)

    @property
    def _batched(self):
        return getattr(self._backend, "batched", False)

    @property
    def envs(self):
        if self._batched:
            return self._backend.clients
        return self._backend.envs

    @property
    def unwrapped(self):
        return self

    @property
    def np_random(self):
        """The vector env's generator (seeded by reset(seed=int)); each environment draws from
        its own (environment i's from seed + i)."""
        if self._np_random is None:
            self._np_random, self._np_random_seed = seeding.np_random()
        return self._np_random

    @np_random.setter
    def np_random(self, value):
        self._np_random = value

    # ---- MuJoCo's Python bindings (the `mujoco` package)
    def _in_process_batch(self):
        from urlab_client.inproc import InProcessBatch
        if self._batched and isinstance(self._backend.clients[0], InProcessBatch):
            return self._backend.clients[0]
        return None

    @property
    def model(self):
        """The environments' model as a mujoco.MjModel (a copy: changing it changes nothing
        in the environments). In process: the batch's (urlab_client.inproc.InProcessBatch.model;
        model_of(i) there for environment i's own when the scene randomises); over servers: the
        first server's, from the MJB it sent at hello."""
        if getattr(self, "_mj_model", None) is None:
            batch = self._in_process_batch()
            if batch is not None:
                self._mj_model = batch.model
            elif self._batched:
                from urlab_client.env import model_from_hello
                self._mj_model = model_from_hello(self._backend.clients[0].client.info)
            else:
                self._mj_model = self._backend.envs[0].model
        return self._mj_model

    def data(self, i=0, out=None):
        """Environment i's mjData now as a mujoco.MjData of `model`: a copy of all of it
        (state, contacts, positions and sensors as the last step computed them: mj_forward on it
        brings them to its qpos), for mujoco.Renderer or the bindings' functions; writing to it
        changes nothing in the environments, and a step does not update it (call again). out:
        an MjData to fill instead of a new one. In-process vector envs only
        (UrlabVectorEnv.in_process, gymnasium.make_vec of a URLab id)."""
        self._need_open("data")
        batch = self._in_process_batch()
        if batch is None:
            raise NotImplementedError("data(i) needs an in-process vector env "
                                      "(UrlabVectorEnv.in_process); over servers, `model` "
                                      "is the servers' model")
        return batch.data(i, out=out)

    # ---- gymnasium's vector API
    def reset(self, *, seed=None, options=None):
        """seed: None, an int (env i gets seed + i) or a list; options: UrlabEnv.reset's, plus
        "reset_mask" (reset only those envs; the others keep their observation)."""
        self._need_open("reset")
        if isinstance(seed, (int, np.integer)):
            self._np_random, self._np_random_seed = seeding.np_random(int(seed))
        if self._batched:
            return self._backend.reset(seed, options)
        if seed is None:
            seeds = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", np.ones(self.num_envs, dtype=bool)), bool)
        infos = [{} for _ in range(self.num_envs)]
        which = [i for i in range(self.num_envs) if mask[i]]
        for i in which:
            self._backend.envs[i].send_reset(options, seed=seeds[i])
        for i in which:
            self._last_obs[i], infos[i] = self._backend.envs[i].receive_reset()
            self._autoreset[i] = False
        return _stack(self._last_obs), _batch_infos(infos)

    def step(self, actions):
        self._need_open("step")
        if self._batched:
            return self._backend.step(actions)
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != self.action_space.shape:
            raise ValueError(f"actions of shape {actions.shape}, expected "
                             f"{self.action_space.shape}")
        n = self.num_envs
        rewards = np.zeros(n, dtype=np.float64)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        infos = [{} for _ in range(n)]
        resetting = self._autoreset.copy()
        sent = np.zeros(n, dtype=bool)
        # 1. Send: a reset where the last step ended an episode, else the action.
        for i in range(n):
            try:
                if resetting[i]:
                    if self._backend.envs[i].client is None:  # its server was lost
                        self._backend.renew(i)
                    self._backend.envs[i].send_reset()
                else:
                    self._backend.envs[i].send_step(actions[i])
                sent[i] = True
            except LOST:
                self._lose(i, truncated, infos)
        # 2. Gather.
        for i in range(n):
            if not sent[i]:
                continue
            env = self._backend.envs[i]
            try:
                if resetting[i]:
                    self._last_obs[i], infos[i] = env.receive_reset()
                else:
                    (self._last_obs[i], rewards[i], terminated[i], truncated[i],
                     infos[i]) = env.receive_step()
            except LOST:
                self._lose(i, truncated, infos)
            except UrlabError as e:
                if e.code not in ("session_expired", "shutting_down"):
                    raise
                self._lose(i, truncated, infos)
        self._autoreset = terminated | truncated
        return _stack(self._last_obs), rewards, terminated, truncated, _batch_infos(infos)

    # ---- Asynchronous stepping over batched servers (EnvPool's send/recv; gymnasium's
    # step_async/step_wait). Between send() and recv() the servers step while Python works:
    # with two servers of N/2 environments, one steps its half while Python handles the other's.
    def _require_batched(self, what):
        if not self._batched:
            raise NotImplementedError(f"{what}() needs a vector env over batched servers "
                                      "(UrlabVectorEnv.over_batch)")

    def send(self, actions, env_id=None):
        """Sends a step for the environments env_id (whole servers' environments, in order, as
        recv() gave them in infos["env_id"]; None: every environment) and returns at once.
        actions: (len(env_id), nu). At most one send() per server waits for its recv()."""
        self._need_open("send")
        self._require_batched("send")
        self._backend.send(actions, env_id)

    def recv(self):
        """The replies to send(), one server at a time in the order sent: (obs, rewards,
        terminated, truncated, infos) over that server's environments, infos["env_id"] their
        indices. Autoreset and flags are step()'s, environment by environment."""
        self._need_open("recv")
        self._require_batched("recv")
        return self._backend.recv()

    def step_async(self, actions):
        """gymnasium's first half of step(): sends every environment's action, returns at once."""
        self._need_open("step_async")
        self._require_batched("step_async")
        self._backend.send(actions, None)

    def step_wait(self):
        """The second half: step()'s result for the actions step_async sent."""
        self._need_open("step_wait")
        self._require_batched("step_wait")
        parts = [self._backend.recv() for _ in range(len(self._backend.clients))]
        order = np.argsort([int(p[4]["env_id"][0]) for p in parts], kind="stable")
        parts = [parts[i] for i in order]
        if isinstance(parts[0][0], dict):
            obs = OrderedDict((key, np.concatenate([p[0][key] for p in parts]))
                              for key in parts[0][0])
        else:  # a task's observation array
            obs = np.concatenate([p[0] for p in parts])
        rewards, terminated, truncated = (np.concatenate([p[j] for p in parts]) for j in (1, 2, 3))
        infos = {}
        keys = [k for p in parts for k in p[4] if not k.startswith("_") and k != "env_id"]
        for key in dict.fromkeys(keys):
            values, masks = [], []
            for p in parts:
                m = len(p[1])
                if key in p[4]:
                    values.append(np.asarray(p[4][key]))
                    masks.append(np.asarray(p[4]["_" + key], dtype=bool))
                else:
                    values.append(np.zeros(m, dtype=np.asarray(
                        next(q[4][key] for q in parts if key in q[4])).dtype))
                    masks.append(np.zeros(m, dtype=bool))
            infos[key] = np.concatenate(values)
            infos["_" + key] = np.concatenate(masks)
        return obs, rewards, terminated, truncated, infos

    def _lose(self, i, truncated, infos):
        """Sub-environment i's server is gone: its episode ends as truncated, with its last
        observation; it comes back (a replacement server) at its autoreset."""
        if self._backend.replace is None:
            raise RuntimeError(f"environment {i}: its server ({self._backend.envs[i].endpoint}) "
                               "stopped answering, and this vector env has no replace callback")
        env = self._backend.envs[i]
        try:
            env.client._socket.close(0)
        except Exception:  # noqa: BLE001
            pass
        env.client = None
        truncated[i] = True
        infos[i] = {"server_lost": True}
        if self._last_obs[i] is None:
            self._last_obs[i] = env.observation_space.sample()

    def _need_open(self, what):
        if getattr(self, "closed", False):
            raise RuntimeError(f"{what}() on a closed UrlabVectorEnv")

    def close(self, **kwargs):
        if getattr(self, "closed", True):
            return
        self.closed = True
        try:
            if self._batched:
                self._backend.close()
                return
            for env in self._backend.envs:
                if env.client is not None:
                    env.close()
        finally:
            if self._on_close:
                self._on_close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001
            pass
