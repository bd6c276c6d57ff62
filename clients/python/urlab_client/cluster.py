"""URLab servers on a Dask cluster, and a vector env over them (Debian: python3-distributed).

    from distributed import Client, LocalCluster
    from urlab_client.cluster import ServerPool

    with Client(LocalCluster(n_workers=2, threads_per_worker=1)) as client:
        pool = ServerPool(client, "examples/scenes/arm.yaml", n=32, urlab="./build/urlab")
        with pool.vector_env("arm", frame_skip=5) as envs:   # a UrlabVectorEnv of 32
            obs, infos = envs.reset(seed=0)
            ...

The same code runs on any Dask cluster: an SSH cluster, Slurm or PBS through dask-jobqueue,
Kubernetes through dask-kubernetes (docs/cluster.md). Each server is one long-running task: it
starts `urlab run SCENE --ports auto --announce FILE` on its worker, publishes the announced
endpoints under the slot's name (the scheduler's metadata), leaves the worker's thread pool
(secede) and watches the process until the pool closes. The process dies with its worker
(PR_SET_PDEATHSIG). When a worker dies, the scheduler runs its tasks again on a live worker (or
the restarted one); the vector env sees those servers stop answering, ends their episodes as
truncated and reconnects each sub-environment to its slot's new server at its autoreset.

Batched servers: `ServerPool(..., envs_per_server=16)` starts each server with `--envs 16`
(many environments in one process, urlab_client.batch) and `pool.batch_vector_env()` returns a
vector env over all of them (n servers x 16 environments); a lost server's environments end
truncated and come back on its slot's replacement at their autoreset. Each steps on its share of
its machine's cores (`--threads`: the cores over the pool's servers on that machine), and a worker
hosting a server pauses its statistical profiler (CPU the server needs, spent on sampling a
thread that only waits).

Reaching the servers: the announced endpoints are the ones bound. A scene binding loopback
(`tcp://127.0.0.1:*`, the default of `--ports auto` for the step server) is reachable only on the
worker's machine; for workers on other machines bind the step server to every interface
(`network: {rpc: "tcp://*:*"}`): a wildcard host is replaced by the worker's address.
"""
import ctypes
import json
import os
import signal
import subprocess
import tempfile
import time
import uuid
from urllib.parse import urlparse



def _die_with_parent():
    """In the child before exec: SIGTERM when the worker process that started it dies."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def _reachable(endpoint, host):
    """A wildcard bind (tcp://0.0.0.0:p, tcp://*:p, tcp://[::]:p) as tcp://host:p."""
    if not endpoint or not endpoint.startswith("tcp://"):
        return endpoint
    bound, _, port = endpoint[len("tcp://"):].rpartition(":")
    if bound in ("0.0.0.0", "*", "[::]", "::") and host:
        return f"tcp://{host}:{port}"
    return endpoint


def start_server(urlab, scene, args=(), announce_timeout=120.0, log_dir=None, command="run"):
    """Starts `urlab COMMAND SCENE --ports auto --announce FILE ARGS...` here (COMMAND: run or
    record); returns (process, announce dict, with "log": the process's output file) once the
    file appears. Raises RuntimeError with the log's end if it exits first. The process dies
    with this one (PR_SET_PDEATHSIG)."""
    folder = tempfile.mkdtemp(prefix="urlab_server_", dir=log_dir)
    announce = os.path.join(folder, "announce.json")
    log_path = os.path.join(folder, "urlab.log")
    with open(log_path, "wb") as log:
        proc = subprocess.Popen([urlab, command, scene, "--ports", "auto", "--announce", announce,
                                 *args], stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, preexec_fn=_die_with_parent)
    deadline = time.monotonic() + announce_timeout
    while True:
        if os.path.exists(announce):
            with open(announce) as f:
                info = json.load(f)
            info["log"] = log_path
            return proc, info
        if proc.poll() is not None or time.monotonic() > deadline:
            if proc.poll() is None:
                proc.kill()
            with open(log_path, errors="replace") as f:
                tail = f.read()[-2000:]
            raise RuntimeError(f"urlab run {scene} did not announce its endpoints "
                               f"(exit {proc.poll()}):\n{tail}")
        time.sleep(0.05)


def _cores():
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def server_threads(cores, servers_here):
    """The stepping threads of each batched server when `servers_here` of them share `cores`
    (`urlab run --threads` defaults to every core, which would oversubscribe them): an even
    share, at least one."""
    return max(1, int(cores) // max(1, int(servers_here)))


# The worker's statistical profiler samples every thread's stack 100 times a second on the
# worker's event loop: CPU taken from the server beside it, for nothing (a server is not a
# computation). It is paused while the worker hosts a server.
_PROFILER = ("profile", "profile-cycle")
_hosting = {"servers": 0}


def _host(worker, delta):
    """Counts the servers this worker process hosts; pauses its profiler while there are any
    and resumes it after the last (on the worker's event loop: Tornado's callbacks are not
    thread-safe)."""
    import threading
    lock = _hosting.setdefault("lock", threading.Lock())
    with lock:
        before = _hosting["servers"]
        _hosting["servers"] = after = before + delta
    if (before == 0) == (after == 0):
        return
    for name in _PROFILER:
        callback = getattr(worker, "periodic_callbacks", {}).get(name)
        if callback is not None:
            worker.loop.add_callback(callback.stop if after else callback.start)


def _serve(slot, variable, stop, urlab, scene, args, servers_here=None):
    """A Dask task: one URLab server for `slot`, until the pool's stop event is set.
    servers_here: for a batched server started without --threads, the pool's servers on this
    host (the server then steps on its share of the cores)."""
    import distributed
    worker = distributed.get_worker()
    if servers_here is not None and "--threads" not in args:
        args = [*args, "--threads", str(server_threads(_cores(), servers_here))]
    proc, info = start_server(urlab, scene, args)
    host = urlparse(worker.address).hostname
    info["endpoints"] = {k: _reachable(v, host) for k, v in info["endpoints"].items()}
    info["worker"] = worker.address
    info["slot"] = slot
    distributed.get_client().set_metadata(variable, info)
    distributed.secede()  # a server is not a computation: free the worker's thread
    event = distributed.Event(stop)
    _host(worker, +1)
    try:
        while proc.poll() is None:
            if event.wait(timeout=0.5):
                break
    finally:
        _host(worker, -1)
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
    if proc.returncode not in (0, -signal.SIGTERM, 128 + signal.SIGTERM) and not event.is_set():
        raise RuntimeError(f"slot {slot}: urlab exited with {proc.returncode} (log {info['log']})")
    return {"slot": slot, "worker": info["worker"], "exit": proc.returncode}


class ServerPool:
    """n URLab servers of one scene, as long-running tasks on a Dask cluster.

    client: a distributed.Client. urlab: the binary on the workers. args: more `urlab run`
    arguments (default: --no-cameras --max-speed). spread: place the slots round robin over the
    workers present now (a slot still moves to another worker when its own dies).
    envs_per_server: each server holds that many environments (`urlab run --envs M`, stepped
    by `threads` threads; see batch_vector_env). threads None: each server steps on its share of
    its host's cores (the cores over the pool's servers placed on that host, at least 1), so
    that servers sharing a machine do not oversubscribe it."""

    def __init__(self, client, scene, n, urlab="urlab", args=("--no-cameras", "--max-speed"),
                 spread=True, name=None, envs_per_server=None, threads=None):
        self.client = client
        self.scene = os.path.abspath(scene)
        self.n = int(n)
        self.urlab = urlab
        self.args = list(args)
        self.envs_per_server = envs_per_server
        if envs_per_server is not None:
            self.args += ["--envs", str(int(envs_per_server))]
            if threads is not None:
                self.args += ["--threads", str(int(threads))]
        self.name = name or f"urlab-{uuid.uuid4().hex[:8]}"
        self._stop = f"{self.name}-stop"
        self._variables = [f"{self.name}-slot-{i}" for i in range(self.n)]
        info = client.scheduler_info()["workers"]
        workers = sorted(info) if spread else []
        # The pool's servers per host (round robin over the workers), for --threads.
        per_host = {}
        for i in range(self.n):
            host = info[workers[i % len(workers)]].get("host") if workers else None
            per_host[host] = per_host.get(host, 0) + 1
        self.futures = []
        for i in range(self.n):
            placement = {}
            host = None
            if workers:
                placement = {"workers": [workers[i % len(workers)]], "allow_other_workers": True}
                host = info[workers[i % len(workers)]].get("host")
            auto = workers and envs_per_server is not None and threads is None
            share = per_host[host] if auto else None
            self.futures.append(client.submit(
                _serve, i, self._variables[i], self._stop, self.urlab, self.scene, self.args,
                share, key=f"{self.name}-serve-{i}", pure=False, retries=5, **placement))
        self._closed = False

    def announced(self, i, timeout=180.0, not_session=None):
        """Slot i's announce (endpoints, session, worker), waiting for it; with not_session,
        waits for a server other than that one (the slot's replacement)."""
        deadline = time.monotonic() + timeout
        while True:
            info = self.client.get_metadata(self._variables[i], default=None)
            if info and info.get("session") != not_session:
                return info
            if self.futures[i].status == "error":
                raise RuntimeError(f"slot {i}: {self.futures[i].exception()}")
            if time.monotonic() > deadline:
                raise TimeoutError(f"slot {i}: no server announced in {timeout} s")
            time.sleep(0.1)

    def endpoints(self):
        return [self.announced(i)["endpoints"]["rpc"] for i in range(self.n)]

    def env(self, i, articulation, not_session=None, **env_options):
        """A UrlabEnv on slot i's server, requiring that server's identity."""
        from urlab_client.env import UrlabEnv
        info = self.announced(i, not_session=not_session)
        env = UrlabEnv(articulation, endpoint=info["endpoints"]["rpc"],
                       require={"server_session": info["session"]}, **env_options)
        env.server_session = info["session"]
        return env

    def vector_env(self, articulation, close_pool=True, **env_options):
        """A UrlabVectorEnv over every slot; a lost server is replaced by its slot's next one.
        close_pool: closing the vector env also stops the servers."""
        env_options.setdefault("timeout", 10.0)
        envs = []
        try:
            for i in range(self.n):
                envs.append(self.env(i, articulation, **env_options))
        except BaseException:
            for e in envs:
                e.close()
            raise

        def replace(i):
            old = vec.envs[i]
            return self.env(i, articulation, not_session=getattr(old, "server_session", None),
                            **env_options)

        from urlab_client.vector import UrlabVectorEnv
        vec = UrlabVectorEnv(envs, replace=replace, on_close=self.close if close_pool else None)
        return vec

    def batch_client(self, i, not_session=None, **options):
        """A urlab_client.batch.BatchClient on slot i's (batched) server, requiring its identity."""
        from urlab_client.batch import BatchClient
        info = self.announced(i, not_session=not_session)
        c = BatchClient(info["endpoints"]["rpc"], require={"server_session": info["session"]},
                        **options)
        c.server_session = info["session"]
        return c

    def batch_vector_env(self, close_pool=True, reward_fn=None, terminated_fn=None,
                         max_episode_steps=None, task=None, **options):
        """A UrlabVectorEnv over every environment of every slot (start the pool with
        envs_per_server): environments k*M .. k*M+M-1 are slot k's. options: BatchClient's
        (frame_skip, timeout, shared_memory, ...). task: a bundled task (its name, e.g.
        "ArmReach", or a urlab_client.tasks.Task; the pool's scene must be the task's) gives the
        actions, observation, reward and termination, as gymnasium.make_vec(id) does in process.
        A lost server's environments end truncated and come back on its slot's replacement."""
        from urlab_client.batch import BatchBackend
        if task is not None:
            from urlab_client.tasks import task_of
            task = task_of(task)
            if options.get("frame_skip") is None:
                options["frame_skip"] = task.frame_skip
        options.setdefault("timeout", 10.0)
        clients = []
        try:
            for i in range(self.n):
                clients.append(self.batch_client(i, **options))
        except BaseException:
            for c in clients:
                c.close()
            raise

        def replace(k):
            old = backend.clients[k]
            return self.batch_client(k, not_session=getattr(old, "server_session", None),
                                     **options)

        backend = BatchBackend(clients, replace=replace, reward_fn=reward_fn,
                               terminated_fn=terminated_fn, max_episode_steps=max_episode_steps,
                               task=task)
        from urlab_client.vector import UrlabVectorEnv
        return UrlabVectorEnv(backend=backend, on_close=self.close if close_pool else None)

    def close(self, timeout=60.0):
        """Stops every server (their tasks end) and forgets the slots."""
        if self._closed:
            return
        self._closed = True
        import distributed
        try:
            distributed.Event(self._stop, client=self.client).set()
            distributed.wait(self.futures, timeout=timeout)
        except Exception:  # noqa: BLE001 - a cluster already gone, or tasks still running
            pass
        for name in self._variables:  # the announces of servers that are gone
            try:
                self.client.set_metadata(name, None)
            except Exception:  # noqa: BLE001
                pass
        self.client.cancel([f for f in self.futures if not f.done()])

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def vector_env(client, scene, articulation, n, urlab="urlab", args=("--no-cameras", "--max-speed"),
               **env_options):
    """n servers of `scene` on the cluster behind `client` and a UrlabVectorEnv over them
    (closing it stops the servers)."""
    pool = ServerPool(client, scene, n, urlab=urlab, args=args)
    try:
        return pool.vector_env(articulation, **env_options)
    except BaseException:
        pool.close()
        raise


def batch_vector_env(client, scene, n, envs_per_server=16, threads=None, urlab="urlab",
                     args=("--no-cameras", "--max-speed"), **options):
    """n batched servers of `scene` (envs_per_server environments each) on the cluster behind
    `client` and a UrlabVectorEnv over all n x envs_per_server environments (closing it stops the
    servers)."""
    pool = ServerPool(client, scene, n, urlab=urlab, args=args, envs_per_server=envs_per_server,
                      threads=threads)
    try:
        return pool.batch_vector_env(**options)
    except BaseException:
        pool.close()
        raise
