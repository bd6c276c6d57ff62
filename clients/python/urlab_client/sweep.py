"""`urlab sweep SWEEP.yaml`: an evaluation grid (scenes x seeds x policies) mapped over a Dask
cluster; one recording per cell and a results table (CSV), with progress.

A sweep file (paths relative to it):

    scenes: [../examples/scenes/arm_lockstep.yaml]
    seeds: [0, 1, 2]
    duration: 2.0                  # simulated seconds per cell
    policies:
      - name: sine
        command: /usr/bin/python3 ../examples/python/sweep_policy.py --amplitude 0.5
      - {name: still, command: /usr/bin/python3 ../examples/python/sweep_policy.py --amplitude 0}
    articulation: arm              # given to the policies (URLAB_ARTICULATION)
    output: sweep-out              # recordings (SCENE-sSEED-POLICY.urrec) and results.csv
    cluster: {workers: 2}          # a LocalCluster of 2 workers; or {scheduler: tcp://host:8786}

Each cell runs `urlab record SCENE --ports auto --announce FILE --step-mode direct -o CELL.urrec`
on a worker (the physics steps only when the policy asks), then the policy command (through the shell, in the sweep file's folder) with these
environment variables: URLAB_ENDPOINT (the step server), URLAB_SERVER_SESSION (to require),
URLAB_SEED, URLAB_DURATION, URLAB_ARTICULATION, URLAB_SCENE, URLAB_CELL. The policy drives the
simulation for URLAB_DURATION simulated seconds (urlab_client.sweep.policy_env() makes the
UrlabEnv for it) and may print one JSON object as its last line of output: its keys become
columns of the table. Then the recording is closed. A cell that fails (the policy's exit code,
the recording) is a row with status "failed" and the reason; the sweep exits 1 if any failed.
On a cluster of several machines the paths must be the same on every worker (a shared folder).
"""
import argparse
import csv
import json
import os
import re
import signal
import subprocess
import sys
import time


def load_sweep(path):
    """The sweep file as a dict with absolute paths; ValueError naming the file and the key."""
    import yaml
    with open(path) as f:
        spec = yaml.safe_load(f) or {}
    where = os.path.dirname(os.path.abspath(path))

    def need(key, kind):
        if key not in spec:
            raise ValueError(f"{path}: '{key}' is required")
        if not isinstance(spec[key], kind):
            raise ValueError(f"{path}: '{key}' must be a {kind.__name__ if isinstance(kind, type) else 'list'}")
        return spec[key]

    known = {"scenes", "seeds", "duration", "policies", "articulation", "output", "cluster",
             "urlab", "timeout"}
    unknown = sorted(set(spec) - known)
    if unknown:
        raise ValueError(f"{path}: unknown key(s) {unknown}; known: {sorted(known)}")
    scenes = [os.path.normpath(os.path.join(where, s)) for s in need("scenes", list)]
    for s in scenes:
        if not os.path.isfile(s):
            raise ValueError(f"{path}: scenes: no file {s}")
    seeds = need("seeds", list)
    if not all(isinstance(x, int) for x in seeds):
        raise ValueError(f"{path}: seeds must be integers")
    duration = need("duration", (int, float))
    if not duration > 0:
        raise ValueError(f"{path}: duration must be > 0 (simulated seconds)")
    policies = []
    for i, p in enumerate(need("policies", list)):
        if not isinstance(p, dict) or not isinstance(p.get("command"), str):
            raise ValueError(f"{path}: policies[{i}] needs a 'command' (and a 'name')")
        name = str(p.get("name", f"policy{i}"))
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
            raise ValueError(f"{path}: policies[{i}].name '{name}': letters, digits, _ . - only")
        policies.append({"name": name, "command": p["command"]})
    cluster = spec.get("cluster", {"workers": 2})
    if not isinstance(cluster, dict) or set(cluster) - {"workers", "scheduler"}:
        raise ValueError(f"{path}: cluster: {{workers: N}} or {{scheduler: ADDRESS}}")
    return {"scenes": scenes, "seeds": seeds, "duration": float(duration), "policies": policies,
            "articulation": spec.get("articulation"), "where": where,
            "output": os.path.normpath(os.path.join(where, spec.get("output", "sweep-out"))),
            "cluster": cluster,
            "urlab": spec.get("urlab"), "timeout": float(spec.get("timeout", 600))}


def cells(spec):
    for scene in spec["scenes"]:
        for seed in spec["seeds"]:
            for policy in spec["policies"]:
                stem = os.path.splitext(os.path.basename(scene))[0]
                yield {"scene": scene, "seed": seed, "policy": policy,
                       "name": f"{stem}-s{seed}-{policy['name']}"}


def run_cell(cell, spec, urlab):
    """One cell, on a worker: record while the policy drives; returns the results row."""
    from urlab_client.cluster import start_server
    row = {"cell": cell["name"], "scene": cell["scene"], "seed": cell["seed"],
           "policy": cell["policy"]["name"], "duration": spec["duration"], "status": "ok",
           "error": "", "recording": "", "frames": "", "sim_time": "", "wall_s": ""}
    t0 = time.monotonic()
    recording = os.path.join(spec["output"], cell["name"] + ".urrec")
    try:
        proc, info = start_server(urlab, cell["scene"], ["-o", recording, "--step-mode",
                                                        "direct", "--no-cameras"],
                                  command="record")
    except RuntimeError as e:
        row.update(status="failed", error=str(e).splitlines()[0])
        return row
    env = dict(os.environ, URLAB_ENDPOINT=info["endpoints"]["rpc"] or "",
               URLAB_SERVER_SESSION=info["session"], URLAB_SEED=str(cell["seed"]),
               URLAB_DURATION=repr(spec["duration"]), URLAB_SCENE=cell["scene"],
               URLAB_ARTICULATION=spec["articulation"] or "", URLAB_CELL=cell["name"])
    try:
        policy = subprocess.run(cell["policy"]["command"], shell=True, cwd=spec["where"], env=env,
                                capture_output=True, text=True, timeout=spec["timeout"])
        lines = policy.stdout.strip().splitlines()
        if lines:
            try:
                extra = json.loads(lines[-1])
                if isinstance(extra, dict):
                    row.update({f"policy_{k}": v for k, v in extra.items()})
            except ValueError:
                pass
        if policy.returncode != 0:
            err = (policy.stderr.strip().splitlines() or ["(no output)"])[-1]
            row.update(status="failed", error=f"policy exit {policy.returncode}: {err}")
    except subprocess.TimeoutExpired:
        row.update(status="failed", error=f"policy still running after {spec['timeout']} s")
    finally:
        proc.send_signal(signal.SIGINT)  # the recording ends and is renamed into place
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
    with open(info["log"], errors="replace") as f:
        log = f.read()
    m = re.search(r"recording: (\S+) steps=(\d+) sim=([0-9.]+) s", log)
    if m and os.path.isfile(recording):
        row.update(recording=recording, frames=int(m.group(2)), sim_time=float(m.group(3)))
    elif row["status"] == "ok":
        row.update(status="failed", error="no recording was written (see " + info["log"] + ")")
    row["wall_s"] = round(time.monotonic() - t0, 3)
    return row


def policy_env(**options):
    """In a policy command: the UrlabEnv of this cell (from the URLAB_* variables), requiring
    the cell's server, reset with the cell's seed. Returns (env, obs, info, duration): step
    while info["time"] < duration."""
    from urlab_client.env import UrlabEnv
    env = UrlabEnv(os.environ["URLAB_ARTICULATION"], endpoint=os.environ["URLAB_ENDPOINT"],
                   require={"server_session": os.environ["URLAB_SERVER_SESSION"]}, **options)
    obs, info = env.reset(seed=int(os.environ["URLAB_SEED"]))
    return env, obs, info, float(os.environ["URLAB_DURATION"])


def write_table(rows, path):
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    tmp = path + ".part"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    os.replace(tmp, path)


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="urlab sweep", description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("sweep", help="the sweep file (YAML)")
    p.add_argument("--urlab", help="the urlab binary on the workers (default: the one running "
                                   "this sweep, or the sweep file's `urlab`)")
    p.add_argument("--workers", type=int, help="a LocalCluster of this many workers (replaces "
                                               "the sweep file's cluster)")
    p.add_argument("--scheduler", help="a running Dask scheduler's address (replaces the sweep "
                                       "file's cluster)")
    p.add_argument("--output", help="the folder for recordings and results.csv (replaces the "
                                    "sweep file's output)")
    args = p.parse_args(argv)
    try:
        spec = load_sweep(args.sweep)
    except (OSError, ValueError) as e:
        print(f"urlab sweep: error: {e}", file=sys.stderr)
        return 1
    if args.output:
        spec["output"] = os.path.abspath(args.output)
    urlab = args.urlab or os.environ.get("URLAB_BINARY") or spec["urlab"] or "urlab"
    os.makedirs(spec["output"], exist_ok=True)
    import distributed
    cluster = None
    if args.scheduler or (not args.workers and spec["cluster"].get("scheduler")):
        client = distributed.Client(args.scheduler or spec["cluster"]["scheduler"])
    else:
        cluster = distributed.LocalCluster(n_workers=args.workers or spec["cluster"].get("workers", 2),
                                           threads_per_worker=1, dashboard_address=None)
        client = distributed.Client(cluster)
    grid = list(cells(spec))
    print(f"urlab sweep: {len(grid)} cell(s) ({len(spec['scenes'])} scene(s) x "
          f"{len(spec['seeds'])} seed(s) x {len(spec['policies'])} polic(ies)) on "
          f"{len(client.scheduler_info()['workers'])} worker(s); output {spec['output']}",
          flush=True)
    rows = []
    try:
        futures = [client.submit(run_cell, c, spec, urlab, key=f"sweep-{c['name']}", pure=False)
                   for c in grid]
        for done, future in enumerate(distributed.as_completed(futures), 1):
            try:
                row = future.result()
            except Exception as e:  # noqa: BLE001 - the worker's error, as a row
                row = {"cell": "?", "status": "failed", "error": repr(e)}
            rows.append(row)
            print(f"[{done}/{len(grid)}] {row['cell']}: {row['status']}"
                  f"{' (' + row['error'] + ')' if row.get('error') else ''}"
                  f"{' ' + str(row['wall_s']) + ' s' if row.get('wall_s') else ''}", flush=True)
    finally:
        client.close()
        if cluster:
            cluster.close()
    order = {c["name"]: i for i, c in enumerate(grid)}
    rows.sort(key=lambda r: order.get(r.get("cell"), len(order)))
    table = os.path.join(spec["output"], "results.csv")
    write_table(rows, table)
    failed = sum(r["status"] != "ok" for r in rows)
    print(f"urlab sweep: {len(rows) - failed} ok, {failed} failed; results in {table}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
