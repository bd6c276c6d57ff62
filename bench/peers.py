"""`urlab bench peers`: environment steps per second of URLab beside the tools a user would pick
instead, on one machine in one run, on the same physics: one MJCF file (default gymnasium's
Humanoid, humanoid.xml), its timestep, and one frame skip (default 5, Humanoid-v5's).

Peers (each (peer, N) measured in a fresh Python process of its own):
  envpool       EnvPool's Humanoid-v5 (C++ environments, its own thread pool of --threads),
                synchronous step of all N; its model is this run's file (base_path points at it)
  gym_sync      gymnasium's own Humanoid-v5 (xml_file=, frame_skip=) in SyncVectorEnv
  gym_async     the same in AsyncVectorEnv (one process per environment)
  urlab_inproc  URLab's in-process batch through its gymnasium vector env
                (UrlabVectorEnv.in_process, liburlab_batch.so, --threads stepping threads)
  urlab_server  URLab's batched server (`urlab run MODEL --envs N --threads T`, its own process)
                through the Python batch client (UrlabVectorEnv.over_batch, shared memory)
  physics       physics only, alternating in one process on the same trajectories (the same
                initial states and the same actions, no resets): mujoco.rollout with --threads
                threads (row "rollout") and URLab's batch step (row "urlab_physics": the library's
                own step time, InProcessBatch, no Python vector env)

Every environment peer takes uniform random actions in the ctrlrange (one bank of actions, the
same for all), ends an episode when the torso's height leaves (1, 2) (Humanoid-v5's health) or
after 1000 steps, and resets with uniform noise of 0.01 on positions and velocities (next-step
autoreset, gymnasium's default and EnvPool's). The observation and reward differ: gymnasium and
EnvPool build Humanoid-v5's 348 values (com inertia, velocities, actuator and contact forces) and
its reward; URLab returns qpos and qvel with a numpy reward over the batch (forward velocity,
health, control cost).

Prints one row per (peer, N): median, min and max of --repeats measurements of --seconds each,
and the median CPU time per environment step (of the peer's threads and processes, through
psutil: a busy machine changes it less than the wall time), then key=value lines. Progress goes
to stderr.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

PEERS = ("envpool", "gym_sync", "gym_async", "urlab_inproc", "urlab_server", "physics")
HEALTHY_Z = (1.0, 2.0)
RESET_NOISE = 0.01
MAX_EPISODE_STEPS = 1000
ACTION_BANK = 64  # distinct action arrays, cycled


def log(msg):
    print(f"[peers] {msg}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------------
# Helpers shared by the workers


def action_bank(n, low, high, seed=0):
    import numpy as np
    rng = np.random.default_rng(seed)
    return rng.uniform(low, high, size=(ACTION_BANK, n, len(low)))


def cpu_seconds():
    """CPU time (user + system) of this process's threads and its living child processes (an
    AsyncVectorEnv's workers, a batched server): what a figure cost the machine, which a busy
    machine changes less than the wall time. None without psutil (Debian's python3-psutil)."""
    try:
        import psutil
    except ImportError:
        return None
    me = psutil.Process()
    total = 0.0
    for proc in [me] + me.children(recursive=True):
        try:
            t = proc.cpu_times()
            total += t.user + t.system
        except psutil.Error:
            pass
    return total


def per_step_us(cpu0, cpu1, env_steps):
    if cpu0 is None or cpu1 is None or env_steps <= 0:
        return float("nan")
    return (cpu1 - cpu0) / env_steps * 1e6


def timed_loop(step, seconds, n):
    """Calls step(k) for `seconds` of wall time: (environment steps per second, CPU
    microseconds per environment step), n environment steps per call."""
    calls = 0
    cpu0 = cpu_seconds()
    t0 = time.perf_counter()
    end = t0 + seconds
    while True:
        step(calls)
        calls += 1
        now = time.perf_counter()
        if now >= end:
            break
    cpu1 = cpu_seconds()
    return calls * n / (now - t0), per_step_us(cpu0, cpu1, calls * n)


def measure(step, args, n):
    """Warm-up (a fifth of --seconds), then --repeats figures: {"rates": [...], "cpu": [...]}."""
    timed_loop(step, max(0.05, args.seconds / 5), n)
    figures = [timed_loop(step, args.seconds, n) for _ in range(args.repeats)]
    return {"rates": [f[0] for f in figures], "cpu": [f[1] for f in figures]}


def gym_humanoid_xml():
    import gymnasium.envs.mujoco as gm
    return os.path.join(os.path.dirname(gm.__file__), "assets", "humanoid.xml")


def model_facts(model):
    import mujoco
    m = mujoco.MjModel.from_xml_path(model)
    return m, {"nq": m.nq, "nv": m.nv, "nu": m.nu, "timestep": m.opt.timestep}


def ctrl_bounds(model):
    m, _ = model_facts(model)
    return m.actuator_ctrlrange[:, 0].copy(), m.actuator_ctrlrange[:, 1].copy()


# --------------------------------------------------------------------------------------------
# The workers: one (peer, N) each, printing one JSON line on stdout.


def work_envpool(args, n):
    import envpool
    import numpy as np
    # EnvPool reads <base_path>/mujoco/assets_gym/<xml_file>: a folder whose humanoid.xml is a
    # link to this run's model, so that EnvPool steps the very file the others step.
    with tempfile.TemporaryDirectory(prefix="urlab-peers-") as base:
        os.makedirs(os.path.join(base, "mujoco", "assets_gym"))
        os.symlink(os.path.abspath(args.model),
                   os.path.join(base, "mujoco", "assets_gym", "humanoid.xml"))
        env = envpool.make("Humanoid-v5", env_type="gymnasium", num_envs=n, batch_size=n,
                           num_threads=args.threads, seed=0, base_path=base,
                           xml_file="humanoid.xml", frame_skip=args.frame_skip,
                           max_episode_steps=MAX_EPISODE_STEPS,
                           reset_noise_scale=RESET_NOISE, healthy_z_min=HEALTHY_Z[0],
                           healthy_z_max=HEALTHY_Z[1])
        env.reset()
        low, high = env.action_space.low, env.action_space.high
        bank = action_bank(n, low, high)
        ids = np.arange(n, dtype=np.int32)
        result = measure(lambda k: env.step(bank[k % ACTION_BANK], ids), args, n)
        env.close()
    return {**result, "threads": args.threads,
            "extra": {"envpool_version": envpool.__version__,
                      "envpool_mujoco": envpool_mujoco_version()}}


def envpool_mujoco_version():
    """The MuJoCo version EnvPool's gym library is built with (its version string, found in the
    library's bytes: EnvPool links MuJoCo in and does not report it)."""
    import envpool.mujoco as em
    folder = os.path.dirname(em.__file__)
    try:
        with open(os.path.join(folder, "mujoco_gym_envpool.so"), "rb") as f:
            data = f.read()
    except OSError:
        return "unknown"
    found = sorted(set(re.findall(rb"\x00(\d+\.\d+\.\d+)\x00", data)))
    return ",".join(v.decode() for v in found) or "unknown"


def make_gym(args):
    import gymnasium
    return gymnasium.make("Humanoid-v5", xml_file=os.path.abspath(args.model),
                          frame_skip=args.frame_skip, reset_noise_scale=RESET_NOISE,
                          healthy_z_range=HEALTHY_Z, max_episode_steps=MAX_EPISODE_STEPS)


def work_gym(args, n, asynchronous):
    import gymnasium
    fns = [lambda: make_gym(args) for _ in range(n)]
    env = gymnasium.vector.AsyncVectorEnv(fns) if asynchronous else \
        gymnasium.vector.SyncVectorEnv(fns)
    env.reset(seed=0)
    low, high = env.single_action_space.low, env.single_action_space.high
    bank = action_bank(n, low, high)
    result = measure(lambda k: env.step(bank[k % ACTION_BANK]), args, n)
    env.close()
    return {**result, "threads": n if asynchronous else 1}


def urlab_task_fns(nq):
    """Humanoid-v5's termination and a reward of its kind, vectorised over the batch."""
    import numpy as np

    def healthy(qpos):
        z = qpos[:, 2]
        return (HEALTHY_Z[0] < z) & (z < HEALTHY_Z[1])

    def terminated_fn(obs, infos):
        return ~healthy(obs["qpos"])

    def reward_fn(obs, actions, infos):
        return (1.25 * obs["qvel"][:, 0] + 5.0 * healthy(obs["qpos"]) -
                0.1 * np.square(actions).sum(axis=1))

    return reward_fn, terminated_fn


def run_urlab_vector(env, args, n):
    env.reset(seed=0)
    low, high = env.single_action_space.low, env.single_action_space.high
    bank = action_bank(n, low, high)
    return measure(lambda k: env.step(bank[k % ACTION_BANK]), args, n)


def work_urlab_inproc(args, n):
    sys.path.insert(0, args.client)
    from urlab_client import UrlabVectorEnv
    _, facts = model_facts(args.model)
    reward_fn, terminated_fn = urlab_task_fns(facts["nq"])
    env = UrlabVectorEnv.in_process(args.model, n, threads=args.threads, seed=0,
                                    frame_skip=args.frame_skip, reset_noise_scale=RESET_NOISE,
                                    reward_fn=reward_fn, terminated_fn=terminated_fn,
                                    max_episode_steps=MAX_EPISODE_STEPS,
                                    library=args.batch_library or None)
    try:
        result = run_urlab_vector(env, args, n)
        threads = env.unwrapped._backend.clients[0].threads
    finally:
        env.close()
    return {**result, "threads": threads}


def work_urlab_server(args, n):
    sys.path.insert(0, args.client)
    from urlab_client import UrlabVectorEnv
    _, facts = model_facts(args.model)
    reward_fn, terminated_fn = urlab_task_fns(facts["nq"])
    with tempfile.TemporaryDirectory(prefix="urlab-peers-") as folder:
        announce = os.path.join(folder, "announce.json")
        cmd = [args.urlab, "run", args.model, "--envs", str(n), "--threads", str(args.threads),
               "--reset-noise", str(RESET_NOISE), "--seed", "0", "--ports", "auto",
               "--announce", announce, "--no-cameras", "--step-mode", "direct", "--max-speed",
               "--duration", "3600", "--log-level", "warn"]
        server = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            deadline = time.monotonic() + 120
            while not os.path.exists(announce):
                if server.poll() is not None:
                    raise RuntimeError("the batched server exited before announcing: " +
                                       server.stderr.read().decode(errors="replace")[-2000:])
                if time.monotonic() > deadline:
                    raise RuntimeError("the batched server did not announce within 120 s")
                time.sleep(0.02)
            time.sleep(0.05)  # the file is renamed into place whole; read it once more if empty
            with open(announce) as f:
                rpc = json.load(f)["endpoints"]["rpc"]
            env = UrlabVectorEnv.over_batch(rpc, frame_skip=args.frame_skip, reward_fn=reward_fn,
                                            terminated_fn=terminated_fn,
                                            max_episode_steps=MAX_EPISODE_STEPS)
            try:
                result = run_urlab_vector(env, args, n)
                threads = int(env.unwrapped._backend.clients[0].info.get("threads", args.threads))
            finally:
                env.close()
        finally:
            server.terminate()
            try:
                server.wait(timeout=30)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait()
    return {**result, "threads": threads}


def work_physics(args, n):
    """mujoco.rollout and URLab's batch step on the same trajectories, alternating."""
    import mujoco
    import numpy as np
    from mujoco import rollout
    sys.path.insert(0, args.client)
    from urlab_client.inproc import InProcessBatch

    m, facts = model_facts(args.model)
    nq, nv, nu = m.nq, m.nv, m.nu
    fs = args.frame_skip
    batch = InProcessBatch(args.model, envs=n, threads=args.threads, seed=0,
                           reset_noise_scale=RESET_NOISE, auto_reset=False, frame_skip=fs,
                           library=args.batch_library or None)
    try:
        if batch.nu != nu or batch.layout[0][2] != nq or batch.layout[1][2] != nv:
            raise RuntimeError("URLab's scene of the model has other sizes than the model")
        if batch.timestep != m.opt.timestep:
            raise RuntimeError(f"URLab's timestep {batch.timestep} != the model's "
                               f"{m.opt.timestep}")
        first = batch.reset(seeds=[i for i in range(n)])["obs"].copy()
        # The same initial states for mujoco.rollout: URLab's reset states (its noise, seed i).
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        nstate = mujoco.mj_stateSize(m, spec)
        d = mujoco.MjData(m)
        init = np.empty((n, nstate))
        for i in range(n):
            mujoco.mj_resetData(m, d)
            d.qpos[:] = first[i, :nq]
            d.qvel[:] = first[i, nq:nq + nv]
            mujoco.mj_getState(m, d, init[i], spec)
        datas = [mujoco.MjData(m) for _ in range(args.threads)]
        low, high = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
        rng = np.random.default_rng(0)

        with rollout.Rollout(nthread=args.threads) as ro:
            def run_rollout(actions):
                k = actions.shape[1]
                control = np.repeat(actions, fs, axis=1)  # each action held for fs steps
                state = np.empty((n, k * fs, nstate))
                sensordata = np.empty((n, k * fs, m.nsensordata))
                cpu0 = cpu_seconds()
                t0 = time.perf_counter()
                ro.rollout(m, datas, init, control, state=state, sensordata=sensordata)
                dt = time.perf_counter() - t0
                return n * k / dt, per_step_us(cpu0, cpu_seconds(), n * k), state

            def run_urlab(actions):
                k = actions.shape[1]
                batch.reset(seeds=[i for i in range(n)])
                own = 0.0
                cpu0 = cpu_seconds()
                t0 = time.perf_counter()
                for j in range(k):
                    batch.send_step(actions[:, j])
                    own += batch._step_seconds
                wall = time.perf_counter() - t0
                cpu = per_step_us(cpu0, cpu_seconds(), n * k)
                obs = batch.receive_step()["obs"]
                return n * k / own, n * k / wall, cpu, obs

            # Calibration (and warm-up): env steps in --seconds at rollout's pace, probed twice
            # (the first steps, standing, are cheaper than the ones after the fall).
            k = 10
            for _ in range(2):
                probe = rng.uniform(low, high, size=(n, k, nu))
                rate, _, _ = run_rollout(probe)
                k = max(10, int(rate * args.seconds / n / (4 if k == 10 else 1)))
            run_urlab(probe)
            log(f"physics N={n}: {k} env steps per trajectory ({k * fs} physics steps)")
            actions = rng.uniform(low, high, size=(n, k, nu))
            ours, ours_wall, theirs, ratios, ratios_wall = [], [], [], [], []
            ours_cpu, theirs_cpu = [], []
            diff = None
            for r in range(args.repeats):
                if r % 2 == 0:
                    t_rate, t_cpu, state = run_rollout(actions)
                    u_rate, u_wall, u_cpu, obs = run_urlab(actions)
                else:
                    u_rate, u_wall, u_cpu, obs = run_urlab(actions)
                    t_rate, t_cpu, state = run_rollout(actions)
                if diff is None:  # the same trajectories: URLab's last state against rollout's
                    last = state[:, -1, :]
                    diff = float(max(np.max(np.abs(obs[:, :nq] - last[:, 1:1 + nq])),
                                     np.max(np.abs(obs[:, nq:nq + nv] -
                                                   last[:, 1 + nq:1 + nq + nv]))))
                ours.append(u_rate)
                ours_wall.append(u_wall)
                theirs.append(t_rate)
                ours_cpu.append(u_cpu)
                theirs_cpu.append(t_cpu)
                ratios.append(u_rate / t_rate)
                ratios_wall.append(u_wall / t_rate)
        threads = batch.threads
    finally:
        batch.close()
    return {"rates": theirs, "cpu": theirs_cpu, "threads": min(args.threads, n),
            "extra_rows": {"urlab_physics": {"rates": ours, "cpu": ours_cpu, "threads": threads},
                           "urlab_physics_wall": {"rates": ours_wall, "cpu": ours_cpu,
                                                  "threads": threads}},
            "extra": {"ratios": ratios, "ratios_wall": ratios_wall, "max_abs_diff": diff,
                      "env_steps": k}}


WORKERS = {
    "envpool": work_envpool,
    "gym_sync": lambda a, n: work_gym(a, n, False),
    "gym_async": lambda a, n: work_gym(a, n, True),
    "urlab_inproc": work_urlab_inproc,
    "urlab_server": work_urlab_server,
    "physics": work_physics,
}


# --------------------------------------------------------------------------------------------
# The driver


def run_worker(args, peer, n):
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", peer, "--worker-envs", str(n),
           "--model", args.model, "--threads", str(args.threads), "--seconds", str(args.seconds),
           "--repeats", str(args.repeats), "--frame-skip", str(args.frame_skip),
           "--client", args.client, "--batch-library", args.batch_library or "",
           "--urlab", args.urlab or ""]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          timeout=args.timeout)
    for line in proc.stderr.splitlines():
        if line.startswith("[peers]"):
            print(line, file=sys.stderr, flush=True)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (proc.stderr.strip().splitlines() or ["(no output)"])[-1]
        return {"error": f"exit {proc.returncode}: {tail}"}
    return json.loads(lines[-1])


def spread(rates):
    return statistics.median(rates), min(rates), max(rates)


def fmt_num(x):
    return "nan" if x is None or not math.isfinite(x) else f"{x:.4g}"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", default=None, help="the MJCF file every peer steps (default: "
                   "gymnasium's Humanoid, humanoid.xml of the installed gymnasium)")
    p.add_argument("--envs", default="1,16,64", help="environment counts, comma-separated")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seconds", type=float, default=2.0, help="seconds per measurement")
    p.add_argument("--repeats", type=int, default=5, help="measurements per (peer, N)")
    p.add_argument("--frame-skip", type=int, default=5)
    p.add_argument("--skip", default="", help="peers to leave out, comma-separated: " +
                   ", ".join(PEERS))
    p.add_argument("--urlab", default="", help="the urlab binary (for urlab_server)")
    p.add_argument("--batch-library", default="", help="liburlab_batch.so")
    p.add_argument("--client", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                    "..", "clients", "python"))
    p.add_argument("--timeout", type=float, default=1800, help="seconds per (peer, N) at most")
    p.add_argument("--worker", choices=PEERS, help=argparse.SUPPRESS)
    p.add_argument("--worker-envs", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()

    if args.worker:
        result = WORKERS[args.worker](args, args.worker_envs)
        print(json.dumps(result), flush=True)
        return 0

    if args.model is None:
        args.model = gym_humanoid_xml()
    args.model = os.path.abspath(args.model)
    envs = [int(x) for x in args.envs.split(",") if x.strip()]
    skip = {x.strip() for x in args.skip.split(",") if x.strip()}
    unknown = skip - set(PEERS)
    if unknown:
        p.error(f"--skip: unknown peer(s) {sorted(unknown)}; the peers are {', '.join(PEERS)}")
    if any(n < 1 for n in envs) or args.threads < 1 or args.repeats < 1 or args.seconds <= 0:
        p.error("--envs, --threads, --repeats and --seconds must be positive")
    peers = [x for x in PEERS if x not in skip]
    if "urlab_server" in peers and not args.urlab:
        p.error("urlab_server needs --urlab")

    import mujoco
    _, facts = model_facts(args.model)
    log(f"model {args.model}: timestep {facts['timestep']}, frame skip {args.frame_skip}, "
        f"{args.threads} threads, N = {envs}, {args.repeats} x {args.seconds} s per figure")

    results = {}  # (row, n) -> result

    def cpu(row, n):
        """Median CPU microseconds per environment step (None when unknown)."""
        values = [c for c in results.get((row, n), {}).get("cpu", []) if math.isfinite(c)]
        return statistics.median(values) if values else None

    failures = {}
    extras = {}
    for n in envs:
        for peer in peers:
            log(f"{peer} N={n} ...")
            t0 = time.monotonic()
            try:
                r = run_worker(args, peer, n)
            except subprocess.TimeoutExpired:
                r = {"error": f"no result within {args.timeout} s"}
            if "error" in r:
                log(f"{peer} N={n}: failed: {r['error']}")
                failures.setdefault(peer, r["error"])
                continue
            row = "rollout" if peer == "physics" else peer
            results[(row, n)] = r
            for name, sub in r.get("extra_rows", {}).items():
                results[(name, n)] = sub
            extras[(peer, n)] = r.get("extra", {})
            med, lo, hi = spread(r["rates"])
            log(f"{row} N={n}: {med:.0f} env steps/s (median) in {time.monotonic() - t0:.0f} s")

    order = ["envpool", "gym_sync", "gym_async", "rollout", "urlab_physics", "urlab_physics_wall",
             "urlab_inproc", "urlab_server"]
    print(f"{'peer':<20} {'N':>4} {'threads':>7} {'env_steps/s':>12} {'min':>12} {'max':>12} "
          f"{'cpu_us/step':>12}")
    for row in order:
        for n in envs:
            if (row, n) not in results:
                continue
            r = results[(row, n)]
            med, lo, hi = spread(r["rates"])
            print(f"{row:<20} {n:>4} {r['threads']:>7} {med:>12.0f} {lo:>12.0f} {hi:>12.0f} "
                  f"{fmt_num(cpu(row, n)):>12}")

    kv = []
    kv.append(("mujoco", mujoco.__version__))
    kv.append(("model", args.model))
    kv.append(("timestep", facts["timestep"]))
    kv.append(("frame_skip", args.frame_skip))
    kv.append(("threads", args.threads))
    kv.append(("repeats", args.repeats))
    kv.append(("seconds", args.seconds))
    for (peer, n), extra in sorted(extras.items()):
        if peer == "envpool":
            kv.append(("envpool_version", extra.get("envpool_version")))
            kv.append(("envpool_mujoco", extra.get("envpool_mujoco")))
            break
    for row in order:
        for n in envs:
            if (row, n) in results:
                kv.append((f"{row}_n{n}_env_steps_per_s",
                           fmt_num(spread(results[(row, n)]["rates"])[0])))
                kv.append((f"{row}_n{n}_cpu_us_per_env_step", fmt_num(cpu(row, n))))
    for peer, reason in failures.items():
        kv.append((peer, f"unavailable reason={reason!r}"))

    def med(row, n):
        r = results.get((row, n))
        return spread(r["rates"])[0] if r else None

    big = max(envs)
    ours = med("urlab_inproc", big)
    if med("envpool", big) is not None and ours is not None:
        kv.append(("ours_over_envpool", fmt_num(ours / med("envpool", big))))
        # Not measured alternately: the spread of the ratio is that of the two figures.
        o, e = results[("urlab_inproc", big)]["rates"], results[("envpool", big)]["rates"]
        kv.append(("ours_over_envpool_min", fmt_num(min(o) / max(e))))
        kv.append(("ours_over_envpool_max", fmt_num(max(o) / min(e))))
        if cpu("envpool", big) and cpu("urlab_inproc", big):
            # CPU time per environment step, EnvPool's over ours (above 1: ours costs less).
            kv.append(("ours_over_envpool_cpu",
                       fmt_num(cpu("envpool", big) / cpu("urlab_inproc", big))))
        if med("urlab_server", big) is not None:
            kv.append(("server_over_envpool",
                       fmt_num(med("urlab_server", big) / med("envpool", big))))
    elif ours is not None:
        # EnvPool could not run here: the nearest peer that did (a vector env of whole tasks
        # stepped in parallel), so the row still has a comparison.
        for near in ("gym_async", "gym_sync"):
            if med(near, big) is not None:
                kv.append(("nearest_peer", near))
                kv.append(("ours_over_nearest", fmt_num(ours / med(near, big))))
                break
    for n in envs:
        e = extras.get(("physics", n))
        if not e:
            continue
        r_med, r_lo, r_hi = spread(e["ratios"])
        w_med = statistics.median(e["ratios_wall"])
        suffix = "" if n == big else f"_n{n}"
        kv.append((f"ours_over_rollout{suffix}", fmt_num(r_med)))
        kv.append((f"ours_over_rollout{suffix}_min", fmt_num(r_lo)))
        kv.append((f"ours_over_rollout{suffix}_max", fmt_num(r_hi)))
        kv.append((f"ours_over_rollout_wall{suffix}", fmt_num(w_med)))
        if cpu("rollout", n) and cpu("urlab_physics", n):
            kv.append((f"ours_over_rollout_cpu{suffix}",
                       fmt_num(cpu("rollout", n) / cpu("urlab_physics", n))))
        kv.append((f"physics_max_abs_diff{suffix}", fmt_num(e["max_abs_diff"])))
    try:
        kv.append(("load_average_1min", f"{os.getloadavg()[0]:.2f}"))
    except OSError:
        pass
    for key, value in kv:
        print(f"{key}={value}")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
