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


MAX_SWEEP_BYTES = 1 << 20  # a sweep file is a page of YAML
MAX_WORKERS = 64          # a LocalCluster's workers (processes on this machine)
MAX_SECONDS = 86400.0     # duration and timeout: a day at most
MAX_SEED = 2 ** 53 - 1    # seeds are whole numbers a double holds exactly (as the server's)
NAME = re.compile(r"[A-Za-z0-9_.-]+")
ARTICULATION = re.compile(r"[A-Za-z_][A-Za-z0-9_.-]*")


class SweepError(ValueError):
    """A bad sweep file: the message names the file, the line and the field."""


def _read_text(path):
    """The sweep file's text: a regular file (a FIFO or device is refused before it is opened,
    so nothing waits on it), at most MAX_SWEEP_BYTES, UTF-8 text."""
    import stat
    st = os.stat(path)
    if not stat.S_ISREG(st.st_mode):
        raise SweepError(f"{path}: not a regular file (a sweep file is a YAML text file)")
    if st.st_size > MAX_SWEEP_BYTES:
        raise SweepError(f"{path}: {st.st_size} bytes; a sweep file is at most "
                         f"{MAX_SWEEP_BYTES} bytes of YAML")
    with open(path, "rb") as f:
        data = f.read(MAX_SWEEP_BYTES + 1)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise SweepError(f"{path}: not a text file (not UTF-8 at byte {e.start})") from None
    if "\0" in text:
        raise SweepError(f"{path}: not a text file (a NUL byte at {text.index(chr(0))})")
    return text


def load_sweep(path):
    """The sweep file as a dict with absolute paths; SweepError (a ValueError) naming the file,
    the line and the field, like a scene file's errors."""
    import math

    import yaml
    text = _read_text(path)
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        line = f":{mark.line + 1}" if mark else ""
        raise SweepError(f"{path}{line}: YAML syntax error: {e.problem or e.context}") from None
    except yaml.YAMLError as e:
        raise SweepError(f"{path}: YAML error: {e}") from None
    except RecursionError:
        raise SweepError(f"{path}: nested too deeply to be a sweep file") from None
    where = os.path.dirname(os.path.abspath(path))
    constructor = yaml.constructor.SafeConstructor()

    def fail(node, field, message):
        line = f":{node.start_mark.line + 1}" if node is not None else ""
        raise SweepError(f"{path}{line}: {field}: {message}")

    def value(node, field):
        try:
            return constructor.construct_object(node, deep=True)
        except yaml.YAMLError as e:
            fail(node, field, str(e).splitlines()[0])
        except RecursionError:
            fail(node, field, "nested too deeply")

    def seq(node, field):
        if not isinstance(node, yaml.SequenceNode):
            fail(node, field, "must be a list")
        return node.value

    def mapping(node, field):
        if not isinstance(node, yaml.MappingNode):
            fail(node, field, "must be a mapping (key: value)")
        out = {}
        for k, v in node.value:
            key = value(k, field)
            if not isinstance(key, str):
                fail(k, field, f"key {key!r} is not a string")
            if key in out:
                fail(k, f"{field}.{key}" if field else key, "given twice")
            out[key] = v
        return out

    def string(node, field, pattern=None):
        v = value(node, field)
        if not isinstance(v, str) or not v:
            fail(node, field, f"must be a non-empty string (got {v!r})")
        if pattern is not None and not pattern.fullmatch(v):
            fail(node, field, f"'{v}': letters, digits, _ . - only")
        return v

    def number(node, field, high):
        v = value(node, field)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            fail(node, field, f"must be a number of seconds in (0, {high:g}] (got {v!r})")
        if not (math.isfinite(v) and 0 < v <= high):
            fail(node, field, f"{v} is not in (0, {high:g}] (seconds)")
        return float(v)

    def whole(node, field, low, high):
        v = value(node, field)
        if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
            fail(node, field, f"{v!r} is not a whole number in [{low}, {high}]")
        return v

    if root is None:
        raise SweepError(f"{path}: empty; 'scenes', 'seeds', 'duration' and 'policies' are "
                         "required")
    if not isinstance(root, yaml.MappingNode):
        fail(root, "the sweep file", "must be a mapping (scenes, seeds, duration, policies...)")
    spec = mapping(root, "")
    known = ["scenes", "seeds", "duration", "policies", "articulation", "output", "cluster",
             "urlab", "timeout"]
    for key, node in spec.items():
        if key not in known:
            fail(node, f"unknown key '{key}'", f"known: {', '.join(known)}")
    for key in ("scenes", "seeds", "duration", "policies"):
        if key not in spec:
            raise SweepError(f"{path}: '{key}' is required")

    scenes, stems = [], {}
    for i, n in enumerate(seq(spec["scenes"], "scenes")):
        field = f"scenes[{i}]"
        s = os.path.normpath(os.path.join(where, string(n, field)))
        if not os.path.isfile(s):
            fail(n, field, f"no file {s}")
        stem = os.path.splitext(os.path.basename(s))[0]
        if stem in stems:  # cells and recordings are named by it
            fail(n, field, f"{s}: its name '{stem}' is scenes[{stems[stem]}]'s too (each "
                           "cell and recording is named after its scene)")
        stems[stem] = i
        scenes.append(s)
    seeds = []
    for i, n in enumerate(seq(spec["seeds"], "seeds")):
        seed = whole(n, f"seeds[{i}]", 0, MAX_SEED)
        if seed in seeds:
            fail(n, "seeds", f"{seed} given twice")
        seeds.append(seed)
    duration = number(spec["duration"], "duration", MAX_SECONDS)
    policies = []
    for i, n in enumerate(seq(spec["policies"], "policies")):
        entry = mapping(n, f"policies[{i}]")
        for key, node in entry.items():
            if key not in ("name", "command"):
                fail(node, f"policies[{i}]", f"unknown key '{key}' (name, command)")
        if "command" not in entry:
            fail(n, f"policies[{i}]", "needs a 'command' (and a 'name')")
        command = string(entry["command"], f"policies[{i}].command")
        name = f"policy{i}"
        if "name" in entry:
            name = string(entry["name"], f"policies[{i}].name", NAME)
        for j, other in enumerate(policies):
            if other["name"] == name:
                fail(entry.get("name", n), f"policies[{i}].name",
                     f"'{name}' is policies[{j}]'s name too (each cell and recording is "
                     "named after its policy)")
        policies.append({"name": name, "command": command})
    articulation = None
    if "articulation" in spec:
        articulation = string(spec["articulation"], "articulation", ARTICULATION)
    output = "sweep-out"
    if "output" in spec:
        output = string(spec["output"], "output")
    output = os.path.normpath(os.path.join(where, output))
    if os.path.exists(output) and not os.path.isdir(output):
        fail(spec.get("output"), "output", f"{output} is not a folder (the recordings and "
                                           "results.csv go in it)")
    cluster = {"workers": 2}
    if "cluster" in spec:
        entries = mapping(spec["cluster"], "cluster")
        if set(entries) - {"workers", "scheduler"} or len(entries) != 1:
            fail(spec["cluster"], "cluster", "{workers: N} or {scheduler: ADDRESS}")
        if "workers" in entries:
            cluster = {"workers": whole(entries["workers"], "cluster.workers", 1, MAX_WORKERS)}
        else:
            cluster = {"scheduler": string(entries["scheduler"], "cluster.scheduler")}
    urlab = string(spec["urlab"], "urlab") if "urlab" in spec else None
    timeout = number(spec["timeout"], "timeout", MAX_SECONDS) if "timeout" in spec else 600.0
    return {"scenes": scenes, "seeds": seeds, "duration": duration, "policies": policies,
            "articulation": articulation, "where": where, "output": output,
            "cluster": cluster, "urlab": urlab, "timeout": timeout}


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
        if args.workers is not None and not 1 <= args.workers <= MAX_WORKERS:
            raise SweepError(f"--workers {args.workers}: a whole number in [1, {MAX_WORKERS}]")
        if args.output:
            spec["output"] = os.path.abspath(args.output)
            if os.path.exists(spec["output"]) and not os.path.isdir(spec["output"]):
                raise SweepError(f"--output {args.output}: not a folder")
        os.makedirs(spec["output"], exist_ok=True)
    except OSError as e:
        print(f"urlab sweep: error: {e.filename or args.sweep}: {e.strerror or e}",
              file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"urlab sweep: error: {e}", file=sys.stderr)
        return 1
    urlab = args.urlab or os.environ.get("URLAB_BINARY") or spec["urlab"] or "urlab"
    import distributed
    cluster = None
    if args.scheduler or (args.workers is None and spec["cluster"].get("scheduler")):
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
