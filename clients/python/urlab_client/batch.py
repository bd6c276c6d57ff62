"""Batched step servers: many environments in one URLab process (`urlab run SCENE --envs N`),
stepped together by one request (the step server's batch_info, batch_step, batch_reset;
docs/network.md, "Batched environments").

    from urlab_client import UrlabVectorEnv
    envs = UrlabVectorEnv.over_batch("tcp://127.0.0.1:5559")   # every environment of that run
    obs, infos = envs.reset(seed=0)                  # obs["qpos"].shape == (N, nq)
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())

BatchClient speaks the operations to one server; BatchBackend is UrlabVectorEnv's backend over
one or more batched servers (N servers x M environments): one request per server per step, sent
to every server before the replies are gathered, with numpy arrays in and out and no loop over
environments in Python; send()/recv() are the same steps asynchronously (one server's reply at
a time, UrlabVectorEnv.send/recv). Actions are in actuator order, what a client of the scene
sends: every environment runs the scene's controllers, so they are joint targets under a PD,
keyframe or gait controller and controls under none, bounded by their ranges; the observation is {"qpos", "qvel", "sensordata"} of the
whole model, views on the reply's packed array (read-only; .copy() one to modify it). With a
`task` (urlab_client.tasks: what gymnasium.make_vec gives) the actions are the task's (each in
-1..1, scaled to the action's range) and so are the observation, reward and termination.

An episode the batch ended by itself is terminated when it diverged (NaN/Inf or MuJoCo's
instability warnings: infos["diverged"]) and truncated when it reached the batch's own episode
limit (`urlab run --max-episode-steps`).
"""
import warnings
from collections import OrderedDict, deque

import numpy as np
import zmq
from gymnasium import spaces
from gymnasium.utils import seeding

from urlab_client.step import StepClient, UrlabError

_F8 = np.dtype("<f8")
_U4 = np.dtype("<u4")
LOST = (TimeoutError, zmq.ZMQError, ConnectionError)  # ConnectionError: shm.ShmError


def renamed(options, old, new, default):
    """options[new], or options[old] with a deprecation warning (the names gymnasium's MuJoCo
    environments use are the current ones: frame_skip, reset_noise_scale); pops both."""
    value = options.pop(new, None)
    if old in options:
        was = options.pop(old)
        warnings.warn(f"{old}= is deprecated: use {new}=", FutureWarning, stacklevel=3)
        if value is None:
            value = was
    return default if value is None else value


class BatchCalls:
    """step() and reset() in one call, over a batch's send_*/receive_* halves (BatchClient's and
    urlab_client.inproc.InProcessBatch's)."""

    def step(self, actions, reset=None):
        self.send_step(actions, reset)
        return self.receive_step()

    def reset(self, envs=None, seeds=None, auto_reset=None):
        self.send_reset(envs, seeds, auto_reset)
        return self.receive_reset()


class BatchClient(BatchCalls):
    """One batched step server: batch_info at connection, direct mode, then batch requests
    (send_*/receive_* halves so a backend sends to every server before gathering)."""

    def __init__(self, endpoint, require=None, frame_skip=None, **client_options):
        self.endpoint = endpoint
        client_options["frame_skip"] = frame_skip
        self.frame_skip = int(renamed(client_options, "n_steps", "frame_skip", 1))
        if self.frame_skip < 1:
            raise ValueError(f"frame_skip must be at least 1, got {self.frame_skip}")
        self.client = StepClient(endpoint, require=require, **client_options)
        try:
            info = self.info = self.client.call("batch_info")
            self.envs = int(info["envs"])
            self.nu = int(info["nu"])
            self.obs_size = int(info["obs_size"])
            self.layout = [(part["name"], int(part["offset"]), int(part["size"]))
                           for part in info["obs_layout"]]
            self.action_low = np.frombuffer(info["action_low"], _F8).copy()
            self.action_high = np.frombuffer(info["action_high"], _F8).copy()
            # A batch step keeps the server's stepping threads busy: a client on shared memory
            # does not spin through it on a core they need.
            self.client.set_partner_threads(int(info.get("threads", 1)))
            self.client.set_mode("direct")
        except BaseException:
            self.client.close()
            raise

    def _result(self, reply):
        n = self.envs
        # Views on the reply's bytes, no copies (the flags are bytes 0 or 1: read as bool).
        return {"obs": np.frombuffer(reply["obs"], _F8).reshape(n, self.obs_size),
                "done": np.frombuffer(reply["done"], np.bool_),
                "reset": np.frombuffer(reply["reset"], np.bool_),
                "time": np.frombuffer(reply["time"], _F8),
                "episode_steps": np.frombuffer(reply["episode_steps"], _U4),
                "step_seconds": float(reply.get("step_seconds", 0.0))}

    def _parts(self, reply):
        """(obs, done, time, episode_steps) of a reply: what a vector env reads, views on the
        reply's bytes."""
        return (np.frombuffer(reply["obs"], _F8).reshape(self.envs, self.obs_size),
                np.frombuffer(reply["done"], np.bool_), np.frombuffer(reply["time"], _F8),
                np.frombuffer(reply["episode_steps"], _U4))

    def _need_open(self):
        if self.client is None:
            raise RuntimeError(f"the batched server's client ({self.endpoint}) is closed")

    @property
    def n_steps(self):  # the old name of frame_skip
        return self.frame_skip

    def send_step(self, actions, reset=None):
        """actions: (envs, nu) float64; reset: (envs,) bool, those environments reset instead of
        stepping (their actions ignored)."""
        self._need_open()
        if type(actions) is not np.ndarray or actions.dtype != _F8 or \
                not actions.flags.c_contiguous:
            actions = np.ascontiguousarray(actions, dtype=_F8)
        fields = {}
        if self.frame_skip != 1:
            fields["n_steps"] = self.frame_skip
        if reset is not None and np.count_nonzero(reset):
            fields["reset"] = np.ascontiguousarray(reset, dtype=np.uint8).tobytes()
        # The actions' bytes go into the request as they are (no msgpack copy).
        self.client.send_request_bytes("batch_step", "actions", actions, **fields)

    def receive_step(self):
        return self._result(self.client.receive_reply("batch_step"))

    def receive_step_parts(self):
        return self._parts(self.client.receive_reply("batch_step"))

    def receive_reset_parts(self):
        return self._parts(self.client.receive_reply("batch_reset"))

    def send_reset(self, envs=None, seeds=None, auto_reset=None):
        """envs: indices (None: all); seeds: one int or None per listed environment."""
        self._need_open()
        fields = {}
        if envs is not None:
            fields["envs"] = [int(e) for e in envs]
        if seeds is not None:
            fields["seeds"] = [None if s is None else int(s) for s in seeds]
        if auto_reset is not None:
            fields["auto_reset"] = bool(auto_reset)
        self.client.send_request("batch_reset", **fields)

    def receive_reset(self):
        return self._result(self.client.receive_reply("batch_reset"))

    def drop(self):
        """Forgets a server that stopped answering (no bye)."""
        try:
            self.client._socket.close(0)
        except Exception:  # noqa: BLE001
            pass
        self.client = None

    def close(self):
        client, self.client = self.client, None
        if client is not None:
            client.close()


_ALL = {}  # n -> a read-only (n,) array of True: the masks of columns every environment has


def _infos(n, **columns):
    every = _ALL.get(n)
    if every is None:
        every = _ALL[n] = np.ones(n, dtype=bool)
        every.flags.writeable = False
    out = {}
    for key, values in columns.items():
        out[key] = values
        out["_" + key] = every
    return out


class BatchBackend:
    """UrlabVectorEnv's backend over batched servers: environment i of the vector env is
    environment i - offset(k) of server k (servers in the order given).

    reward_fn(obs, actions, infos) -> (N,) and terminated_fn(obs, infos) -> (N,) bool are
    vectorised over the environments; or `task` (urlab_client.tasks.Task) gives the actions,
    observation, reward and termination. max_episode_steps (env steps) truncates; an episode
    the server ended is terminated when it diverged (infos["diverged"]), truncated at the
    server's own episode limit. replace(k): a new BatchClient for server k when it stopped
    answering (None: a lost server raises); its environments end truncated
    (infos["server_lost"]) and come back at their autoreset. Each environment has a generator
    (rngs[i], seeded with seed + i by reset(seed)) that the task draws from at its resets."""

    batched = True

    def __init__(self, clients, replace=None, reward_fn=None, terminated_fn=None,
                 max_episode_steps=None, task=None):
        self.clients = list(clients)
        if not self.clients:
            raise ValueError("a batched vector env needs at least one server")
        first = self.clients[0]
        for k, c in enumerate(self.clients[1:], 1):
            if c.nu != first.nu or c.layout != first.layout:
                raise ValueError(f"server {k} ({c.endpoint}) runs another model than server 0")
        if task is not None and (reward_fn is not None or terminated_fn is not None):
            raise ValueError("give a task or reward_fn / terminated_fn, not both")
        self.replace = replace
        self.reward_fn = reward_fn
        self.terminated_fn = terminated_fn
        self.max_episode_steps = max_episode_steps
        self.task = task
        self.counts = [c.envs for c in self.clients]
        self.offsets = np.cumsum([0] + self.counts)
        self.num_envs = int(self.offsets[-1])
        self.nu = first.nu
        self.obs_size = first.obs_size
        # Each server's own episode limit (physics steps, 0: none): a `done` at it is a
        # truncation, any other a divergence.
        self._limits = [int(c.info.get("max_episode_steps", 0) or 0) for c in self.clients]
        self.rngs = [None] * self.num_envs
        if task is None:
            self.single_action_space = spaces.Box(first.action_low, first.action_high,
                                                  shape=(self.nu,), dtype=np.float64)
            self.single_observation_space = spaces.Dict(OrderedDict(
                (name, spaces.Box(-np.inf, np.inf, shape=(size,), dtype=np.float64))
                for name, _, size in first.layout))
        else:
            sizes = {name: size for name, _, size in first.layout}
            task.check(sizes, first.actuators if hasattr(first, "actuators")
                       else first.info.get("actuators", []))
            low, high = first.action_low, first.action_high
            if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))):
                raise ValueError(f"task {task.name}: every action needs a range (a joint range "
                                 "under a PD controller, else a ctrlrange)")
            self._ctrl_mid, self._ctrl_half = (high + low) / 2, (high - low) / 2
            self.single_action_space = spaces.Box(-1.0, 1.0, shape=(self.nu,), dtype=np.float32)
            self.single_observation_space = task.observation_space(sizes)
            self._state = task.new_state(self.num_envs)
        self._obs = np.zeros((self.num_envs, self.obs_size))
        # The observation's parts as (name, column slice), and each server's rows.
        self._parts = [(name, slice(off, off + size)) for name, off, size in first.layout]
        self._rows = [slice(int(self.offsets[k]), int(self.offsets[k + 1]))
                      for k in range(len(self.clients))]
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._elapsed = np.zeros(self.num_envs, dtype=np.int64)
        self._lost = [False] * len(self.clients)
        self._in_flight = deque()  # send()'s requests not received yet, oldest first

    @classmethod
    def connect(cls, endpoints, require=None, frame_skip=None, replace=None, reward_fn=None,
                terminated_fn=None, max_episode_steps=None, task=None, **client_options):
        if isinstance(endpoints, str):
            endpoints = [endpoints]
        client_options["frame_skip"] = frame_skip
        frame_skip = renamed(client_options, "n_steps", "frame_skip", None)
        if frame_skip is None:
            frame_skip = task.frame_skip if task is not None else 1
        clients = []
        try:
            for k, endpoint in enumerate(endpoints):
                r = require[k] if isinstance(require, (list, tuple)) else require
                clients.append(BatchClient(endpoint, require=r, frame_skip=frame_skip,
                                           **client_options))
            return cls(clients, replace=replace, reward_fn=reward_fn,
                       terminated_fn=terminated_fn, max_episode_steps=max_episode_steps,
                       task=task)
        except BaseException:
            for c in clients:
                c.close()
            raise

    def __len__(self):
        return self.num_envs

    # ---- observations
    def _view(self, obs):
        """{"qpos", "qvel", "sensordata"} as views on the (N, obs_size) array."""
        return {name: obs[:, cols] for name, cols in self._parts}

    def _slice(self, k):
        return self._rows[k]

    def _ends(self, done, steps, k=None):
        """(truncated, diverged or None) from a reply's done flags and episode steps (server k's
        rows, or all servers' rows in order)."""
        if not np.count_nonzero(done):
            return done.copy(), None
        if k is None:
            limit = np.concatenate([np.full(c, lim) for c, lim in zip(self.counts, self._limits)])
        else:
            limit = self._limits[k]
        at_limit = done & (limit > 0) & (steps >= limit)
        return at_limit, done & ~at_limit

    # ---- the task (when there is one)
    def _rng(self, i):
        if self.rngs[i] is None:
            self.rngs[i] = seeding.np_random()[0]
        return self.rngs[i]

    def _task_reset(self, rows):
        """The task's own draws (a reaching target, ...) for the environments `rows` (indices in
        the vector env) that were reset, each from its generator."""
        for i in rows:
            self.task.reset_env(self._state, int(i), self._rng(int(i)))

    def _task_state(self, rows):
        return {key: value[rows] for key, value in self._state.items()}

    def _observation(self, view, rows=slice(None)):
        if self.task is None:
            return view
        return self.task.observation(view, self._task_state(rows))

    def _controls(self, actions):
        """The actions the server gets: a task's (-1..1) scaled to the actions' ranges."""
        if self.task is None:
            return actions
        return self._ctrl_mid + self._ctrl_half * np.clip(actions, -1.0, 1.0)

    def _check_actions(self, actions, rows):
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != (rows, self.nu):
            raise ValueError(f"actions of shape {actions.shape}, expected {(rows, self.nu)}")
        if self.task is not None and not np.all(np.isfinite(actions)):
            raise ValueError("actions must be finite numbers")
        return actions

    def _renew(self, k):
        old = self.clients[k]
        if old.client is not None:
            old.drop()
        self.clients[k] = self.replace(k)
        if self.clients[k].envs != self.counts[k] or self.clients[k].nu != self.nu:
            raise RuntimeError(f"the replacement of server {k} runs another batch")
        self._lost[k] = False

    def _lose(self, k, lost):
        """Server k stopped answering: forgets it (replaced at its environments' autoreset) and
        marks its rows in `lost` ((num_envs,) bool, made here when None); returns `lost`."""
        if self.replace is None:
            raise RuntimeError(f"server {k} ({self.clients[k].endpoint}) stopped answering, "
                               "and this vector env has no replace callback")
        self.clients[k].drop()
        self._lost[k] = True
        if lost is None:
            lost = np.zeros(self.num_envs, dtype=bool)
        lost[self._rows[k]] = True
        return lost

    # ---- gymnasium's vector API (UrlabVectorEnv calls these)
    def reset(self, seed=None, options=None, rngs=None):
        """seed: None, an int (environment i gets seed + i) or one per environment; rngs: the
        generators the task draws from for the environments reset (default: each environment's,
        seeded here with its seed)."""
        self._check_idle("reset")
        n = self.num_envs
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"{len(seeds)} seeds for {n} environments")
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", np.ones(n, dtype=bool)), bool)
        if options:
            raise ValueError(f"unknown reset option(s) {sorted(options)}: reset_mask")
        sent = []
        for k, c in enumerate(self.clients):
            s = self._slice(k)
            which = np.flatnonzero(mask[s])
            if which.size == 0:
                continue
            if self._lost[k]:
                self._renew(k)
                c = self.clients[k]
            envs = None if which.size == c.envs else which
            c.send_reset(envs, [seeds[s.start + int(j)] for j in which])
            sent.append(k)
        time = np.zeros(n)
        new = self._obs.copy()  # the environments not reset keep their observation
        for k in sent:
            r = self.clients[k].receive_reset()
            s = self._slice(k)
            m = mask[s]
            new[s][m] = r["obs"][m]
            time[s] = r["time"]
        self._obs = new
        self._autoreset[mask] = False
        self._elapsed[mask] = 0
        if self.task is not None:
            rows = np.flatnonzero(mask)
            for j, i in enumerate(rows):
                if rngs is not None:
                    self.rngs[i] = rngs[j]
                elif seeds[i] is not None:
                    self.rngs[i] = seeding.np_random(int(seeds[i]))[0]
            self._task_reset(rows)
        return self._observation(self._view(self._obs)), _infos(n, time=time)

    def step(self, actions):
        if self._in_flight:
            self._check_idle("step")
        n = self.num_envs
        actions = self._check_actions(actions, n)
        controls = self._controls(actions)
        # Per step: one request per server, then numpy over all environments at once; the
        # masks of resets and lost servers only when there are any.
        clients, rows = self.clients, self._rows
        single = len(clients) == 1
        resetting = self._autoreset
        any_reset = bool(np.count_nonzero(resetting))
        lost = None
        sent = []
        for k in range(len(clients)):
            try:
                if self._lost[k]:  # its environments were truncated: back at their autoreset
                    self._renew(k)
                    self.clients[k].send_reset()
                    sent.append((k, True))
                else:
                    s = rows[k]
                    clients[k].send_step(controls if single else controls[s],
                                         (resetting if single else resetting[s]) if any_reset
                                         else None)
                    sent.append((k, False))
            except LOST:
                lost = self._lose(k, lost)
        got = [None] * len(clients)
        for k, renewed in sent:
            try:
                c = self.clients[k]
                got[k] = c.receive_reset_parts() if renewed else c.receive_step_parts()
            except LOST:
                lost = self._lose(k, lost)
                continue
            except UrlabError as e:
                if e.code not in ("session_expired", "shutting_down"):
                    raise
                lost = self._lose(k, lost)
                continue
            if renewed:
                if resetting is self._autoreset:
                    resetting = resetting.copy()
                resetting[rows[k]] = True
                any_reset = True
        if single and got[0] is not None:
            obs, done, time, steps = got[0]  # obs, time: the reply's own arrays (read-only)
            truncated, diverged = self._ends(done, steps, 0)  # truncated: a fresh array
        else:  # the servers' rows in order; a lost server's keep their observation
            obs = np.concatenate([got[k][0] if got[k] is not None else self._obs[rows[k]]
                                  for k in range(len(clients))])
            done = np.concatenate([got[k][1] if got[k] is not None
                                   else np.zeros(self.counts[k], dtype=bool)
                                   for k in range(len(clients))])
            time = np.concatenate([got[k][2] if got[k] is not None else np.zeros(self.counts[k])
                                   for k in range(len(clients))])
            steps = np.concatenate([got[k][3] if got[k] is not None
                                    else np.zeros(self.counts[k], dtype=_U4)
                                    for k in range(len(clients))])
            truncated, diverged = self._ends(done, steps)
        self._obs = obs
        elapsed = self._elapsed
        elapsed += 1
        if any_reset:
            elapsed[resetting] = 0
            if self.task is not None:
                self._task_reset(np.flatnonzero(resetting))
        view = self._view(obs)
        infos = _infos(n, time=time)
        rewards, terminated = self._outcome(view, actions, infos, truncated, diverged, lost,
                                            resetting, any_reset, elapsed)
        self._autoreset = terminated | truncated
        return self._observation(view), rewards, terminated, truncated, infos

    def _outcome(self, obs, actions, infos, truncated, diverged, lost, resetting, any_reset,
                 elapsed, rows=slice(None)):
        """Rewards and terminations of one step of len(truncated) environments (step() and
        recv(); rows: theirs in the vector env). `truncated` comes in as the episodes the server
        ended at its limit and is updated in place (max_episode_steps, lost servers); diverged:
        None, or the episodes the server ended otherwise (terminated, infos["diverged"]); lost:
        None, or the environments of servers that stopped answering (infos["server_lost"])."""
        m = len(truncated)
        if self.task is not None:
            state = self._task_state(rows)
            rewards = np.asarray(self.task.reward(obs, actions, state), dtype=np.float64)
            terminated = np.asarray(self.task.terminated(obs, state), dtype=bool).copy()
        else:
            if self.reward_fn is not None:
                rewards = np.asarray(self.reward_fn(obs, actions, infos), dtype=np.float64)
            else:
                rewards = np.zeros(m)
            if self.terminated_fn is not None:
                terminated = np.asarray(self.terminated_fn(obs, infos), dtype=bool).copy()
            else:
                terminated = np.zeros(m, dtype=bool)
        if diverged is not None:
            terminated |= diverged
            infos["diverged"] = diverged
            infos["_diverged"] = diverged.copy()
        if lost is not None:
            truncated |= lost
        if self.max_episode_steps is not None:
            truncated |= elapsed >= self.max_episode_steps
        # The environments that reset in this step: reward 0, not ended (gymnasium's next-step).
        if any_reset:
            rewards[resetting] = 0
            terminated[resetting] = False
            truncated[resetting if lost is None else resetting & ~lost] = False
        if lost is not None:
            infos["server_lost"] = lost
            infos["_server_lost"] = lost.copy()
        return rewards, terminated
    # ---- Asynchronous stepping, EnvPool's send/recv (UrlabVectorEnv.send, recv)
    def _check_idle(self, what):
        if self._in_flight:
            raise RuntimeError(f"{what}() while {len(self._in_flight)} send() request(s) wait "
                               "for recv()")

    def _servers_of(self, env_id):
        """The servers whose environments env_id lists (whole servers, in their order)."""
        if env_id is None:
            return list(range(len(self.clients)))
        ids = np.asarray(env_id, dtype=np.int64).ravel()
        ks, at = [], 0
        while at < ids.size:
            k = int(np.searchsorted(self.offsets, ids[at], side="right")) - 1
            s = self._slice(k) if 0 <= k < len(self.clients) else None
            if s is None or ids[at] != s.start or \
                    not np.array_equal(ids[at:at + self.counts[k]], np.arange(s.start, s.stop)):
                raise ValueError("env_id must list whole servers' environments in order (as "
                                 f"recv() gives them in infos['env_id']); got {ids.tolist()}")
            ks.append(k)
            at += self.counts[k]
        if len(set(ks)) != len(ks):
            raise ValueError(f"env_id lists a server twice: {ids.tolist()}")
        return ks

    def send(self, actions, env_id=None):
        """Sends a step to the servers of env_id (None: all) and returns without waiting; their
        replies come back one server at a time from recv(), in the order sent. At most one
        request per server is in flight."""
        ks = self._servers_of(env_id)
        actions = self._check_actions(actions, sum(self.counts[k] for k in ks))
        controls = self._controls(actions)
        busy = {entry[0] for entry in self._in_flight}
        for k in ks:
            if k in busy:
                raise RuntimeError(f"server {k} has a step in flight already: recv() it first")
        at = 0
        for k in ks:
            a = actions[at:at + self.counts[k]]
            c = controls[at:at + self.counts[k]]
            at += self.counts[k]
            resetting = self._autoreset[self._slice(k)].copy()
            renewed, failed = False, False
            try:
                if self._lost[k]:  # its environments were truncated: back at their autoreset
                    self._renew(k)
                    self.clients[k].send_reset()
                    renewed = True
                else:
                    self.clients[k].send_step(c, resetting)
            except LOST:
                failed = True
            self._in_flight.append((k, renewed, failed, a, resetting))

    def recv(self):
        """The oldest send()'s reply for one server: (obs, rewards, terminated, truncated, infos)
        over that server's environments only, infos["env_id"] their indices in the vector env;
        the same autoreset and flags as step() gives those environments."""
        if not self._in_flight:
            raise RuntimeError("recv() with no send() waiting for its reply")
        k, renewed, failed, actions, resetting = self._in_flight.popleft()
        s, m = self._rows[k], self.counts[k]
        lost = diverged = None
        if not failed:
            try:
                c = self.clients[k]
                obs, done, time, steps = c.receive_reset_parts() if renewed else \
                    c.receive_step_parts()
                truncated, diverged = self._ends(done, steps, k)
                time = time.copy()
                if renewed:
                    resetting = np.ones(m, dtype=bool)
            except LOST:
                failed = True
            except UrlabError as e:
                if e.code not in ("session_expired", "shutting_down"):
                    raise
                failed = True
        if failed:
            lost = self._lose(k, None)[s]
            obs, truncated, time = self._obs[s].copy(), np.zeros(m, dtype=bool), np.zeros(m)
            diverged = None
        if not self._obs.flags.writeable:  # a reply's own array after step()
            self._obs = self._obs.copy()
        self._obs[s] = obs
        elapsed = self._elapsed[s]  # a view: updated in place
        elapsed += 1
        any_reset = bool(np.count_nonzero(resetting))
        if any_reset:
            elapsed[resetting] = 0
            if self.task is not None:
                self._task_reset(s.start + np.flatnonzero(resetting))
        view = self._view(obs)  # the reply's own array: later replies leave it as it is
        infos = _infos(m, time=time, env_id=np.arange(s.start, s.stop))
        rewards, terminated = self._outcome(view, actions, infos, truncated, diverged, lost,
                                            resetting, any_reset, elapsed, rows=s)
        self._autoreset[s] = terminated | truncated
        return self._observation(view, s), rewards, terminated, truncated, infos

    def close(self):
        # Replies still owed to send() are taken first: a client has one request in flight at a
        # time (over ZeroMQ the bye could not be sent, and the lease would stay taken).
        while self._in_flight:
            k, renewed, failed, *_ = self._in_flight.popleft()
            client = self.clients[k]
            if failed or client.client is None:
                continue
            try:
                client.receive_reset() if renewed else client.receive_step()
            except (UrlabError,) + LOST:
                pass
        for c in self.clients:
            c.close()
