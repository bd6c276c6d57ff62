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
a time, UrlabVectorEnv.send/recv). Actions are the model's controls (ctrl, actuator order)
bounded by each actuator's ctrlrange; the observation is {"qpos", "qvel", "sensordata"} of the
whole model, views on the reply's packed array (read-only; .copy() one to modify it).
"""
from collections import OrderedDict, deque

import numpy as np
import zmq

from urlab_client import spaces
from urlab_client.step import StepClient, UrlabError

_F8 = np.dtype("<f8")
_U4 = np.dtype("<u4")
LOST = (TimeoutError, zmq.ZMQError, ConnectionError)  # ConnectionError: shm.ShmError


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

    def __init__(self, endpoint, require=None, n_steps=1, **client_options):
        self.endpoint = endpoint
        self.n_steps = int(n_steps)
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
        """(obs, done, time) of a reply: what a vector env reads, views on the reply's bytes."""
        return (np.frombuffer(reply["obs"], _F8).reshape(self.envs, self.obs_size),
                np.frombuffer(reply["done"], np.bool_), np.frombuffer(reply["time"], _F8))

    def send_step(self, actions, reset=None):
        """actions: (envs, nu) float64; reset: (envs,) bool, those environments reset instead of
        stepping (their actions ignored)."""
        if type(actions) is not np.ndarray or actions.dtype != _F8 or \
                not actions.flags.c_contiguous:
            actions = np.ascontiguousarray(actions, dtype=_F8)
        fields = {}
        if self.n_steps != 1:
            fields["n_steps"] = self.n_steps
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
    vectorised over the environments; max_episode_steps (env steps) truncates; an episode the
    server ended (divergence, or its --max-episode-steps) is truncated. replace(k): a new
    BatchClient for server k when it stopped answering (None: a lost server raises); its
    environments end truncated (infos["server_lost"]) and come back at their autoreset."""

    batched = True

    def __init__(self, clients, replace=None, reward_fn=None, terminated_fn=None,
                 max_episode_steps=None):
        self.clients = list(clients)
        if not self.clients:
            raise ValueError("a batched vector env needs at least one server")
        first = self.clients[0]
        for k, c in enumerate(self.clients[1:], 1):
            if c.nu != first.nu or c.layout != first.layout:
                raise ValueError(f"server {k} ({c.endpoint}) runs another model than server 0")
        self.replace = replace
        self.reward_fn = reward_fn
        self.terminated_fn = terminated_fn
        self.max_episode_steps = max_episode_steps
        self.counts = [c.envs for c in self.clients]
        self.offsets = np.cumsum([0] + self.counts)
        self.num_envs = int(self.offsets[-1])
        self.nu = first.nu
        self.obs_size = first.obs_size
        self.single_action_space = spaces.Box(first.action_low, first.action_high,
                                              shape=(self.nu,), dtype=np.float64)
        self.single_observation_space = spaces.Dict(OrderedDict(
            (name, spaces.Box(-np.inf, np.inf, shape=(size,), dtype=np.float64))
            for name, _, size in first.layout))
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
    def connect(cls, endpoints, require=None, n_steps=1, replace=None, reward_fn=None,
                terminated_fn=None, max_episode_steps=None, **client_options):
        if isinstance(endpoints, str):
            endpoints = [endpoints]
        clients = []
        try:
            for k, endpoint in enumerate(endpoints):
                r = require[k] if isinstance(require, (list, tuple)) else require
                clients.append(BatchClient(endpoint, require=r, n_steps=n_steps,
                                           **client_options))
        except BaseException:
            for c in clients:
                c.close()
            raise
        return cls(clients, replace=replace, reward_fn=reward_fn, terminated_fn=terminated_fn,
                   max_episode_steps=max_episode_steps)

    def __len__(self):
        return self.num_envs

    # ---- observations
    def _view(self, obs):
        """{"qpos", "qvel", "sensordata"} as views on the (N, obs_size) array."""
        return {name: obs[:, cols] for name, cols in self._parts}

    def _slice(self, k):
        return self._rows[k]

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
    def reset(self, seed=None, options=None):
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
        return self._view(self._obs), _infos(n, time=time)

    def step(self, actions):
        if self._in_flight:
            self._check_idle("step")
        n = self.num_envs
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != (n, self.nu):
            raise ValueError(f"actions of shape {actions.shape}, expected {(n, self.nu)}")
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
                    clients[k].send_step(actions if single else actions[s],
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
            obs, truncated, time = got[0]  # obs, time: the reply's own arrays (read-only)
            truncated = truncated.copy()  # updated in place below
        else:  # the servers' rows in order; a lost server's keep their observation
            obs = np.concatenate([got[k][0] if got[k] is not None else self._obs[rows[k]]
                                  for k in range(len(clients))])
            truncated = np.concatenate([got[k][1] if got[k] is not None
                                        else np.zeros(self.counts[k], dtype=bool)
                                        for k in range(len(clients))])
            time = np.concatenate([got[k][2] if got[k] is not None else np.zeros(self.counts[k])
                                   for k in range(len(clients))])
        self._obs = obs
        elapsed = self._elapsed
        elapsed += 1
        if any_reset:
            elapsed[resetting] = 0
        view = self._view(obs)
        infos = _infos(n, time=time)
        rewards, terminated = self._outcome(view, actions, infos, truncated, lost, resetting,
                                            any_reset, elapsed)
        self._autoreset = terminated | truncated
        return view, rewards, terminated, truncated, infos

    def _outcome(self, obs, actions, infos, truncated, lost, resetting, any_reset, elapsed):
        """Rewards and terminations of one step of len(truncated) environments (step() and
        recv()). `truncated` comes in as the episodes the server ended and is updated in place
        (max_episode_steps, lost servers); lost: None, or the environments of servers that
        stopped answering (infos["server_lost"])."""
        m = len(truncated)
        if self.reward_fn is not None:
            rewards = np.asarray(self.reward_fn(obs, actions, infos), dtype=np.float64)
        else:
            rewards = np.zeros(m)
        if self.terminated_fn is not None:
            terminated = np.asarray(self.terminated_fn(obs, infos), dtype=bool).copy()
        else:
            terminated = np.zeros(m, dtype=bool)
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
        rows = sum(self.counts[k] for k in ks)
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != (rows, self.nu):
            raise ValueError(f"actions of shape {actions.shape}, expected {(rows, self.nu)}")
        busy = {entry[0] for entry in self._in_flight}
        for k in ks:
            if k in busy:
                raise RuntimeError(f"server {k} has a step in flight already: recv() it first")
        at = 0
        for k in ks:
            a = actions[at:at + self.counts[k]]
            at += self.counts[k]
            resetting = self._autoreset[self._slice(k)].copy()
            renewed, failed = False, False
            try:
                if self._lost[k]:  # its environments were truncated: back at their autoreset
                    self._renew(k)
                    self.clients[k].send_reset()
                    renewed = True
                else:
                    self.clients[k].send_step(a, resetting)
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
        lost = None
        if not failed:
            try:
                c = self.clients[k]
                obs, truncated, time = c.receive_reset_parts() if renewed else \
                    c.receive_step_parts()
                truncated, time = truncated.copy(), time.copy()
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
        if not self._obs.flags.writeable:  # a reply's own array after step()
            self._obs = self._obs.copy()
        self._obs[s] = obs
        elapsed = self._elapsed[s]  # a view: updated in place
        elapsed += 1
        any_reset = bool(np.count_nonzero(resetting))
        if any_reset:
            elapsed[resetting] = 0
        view = self._view(obs)  # the reply's own array: later replies leave it as it is
        infos = _infos(m, time=time, env_id=np.arange(s.start, s.stop))
        rewards, terminated = self._outcome(view, actions, infos, truncated, lost, resetting,
                                            any_reset, elapsed)
        self._autoreset[s] = terminated | truncated
        return view, rewards, terminated, truncated, infos

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
