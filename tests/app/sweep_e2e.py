#!/usr/bin/python3
"""End to end: `urlab sweep` on a Dask LocalCluster of 2 workers.

A grid of 1 scene x 2 seeds x 3 policies (two that drive the arm, one that fails) for 0.5
simulated seconds: progress lines, one recording per cell that `urlab replay --info` reads,
results.csv with a row per cell (the policies' JSON as columns; the failing cell "failed" with
its reason) and exit 1 because a cell failed; the same seed and policy give the same return in a
second sweep. `--help` is the sweep's own; a bad sweep file names the file and the key.
Usage: sweep_e2e.py URLAB_BINARY SOURCE_DIR
"""
import csv
import os
import subprocess
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


def sweep(path, *extra):
    # Bounded below ctest's limit, so that a sweep that stops making progress shows what it
    # printed so far instead of being killed without a word.
    try:
        return subprocess.run([URLAB, "sweep", path, *extra], capture_output=True, text=True,
                              timeout=270)
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode(errors="replace") if isinstance(e.stdout, bytes) else e.stdout
        err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else e.stderr
        fail(f"urlab sweep {path} still running after {e.timeout} s:\n{out}\n"
             f"{(err or '')[-3000:]}")


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_sweep_")
    # Dask's worker scratch space (its folders and their lock files) for this run alone: test
    # runs sharing the machine never lock or purge each other's.
    os.environ["DASK_TEMPORARY_DIRECTORY"] = os.path.join(tmp, "dask")
    policy = os.path.join(SOURCE, "examples", "python", "sweep_policy.py")
    spec = os.path.join(tmp, "grid.yaml")
    with open(spec, "w") as f:
        f.write(f"""scenes: [{os.path.join(SOURCE, "examples", "models", "servo_arm.xml")}]
seeds: [0, 1]
duration: 0.5
articulation: servo_arm
policies:
  - {{name: sine, command: {sys.executable} {policy} --amplitude 0.5}}
  - {{name: still, command: {sys.executable} {policy} --amplitude 0}}
  - {{name: broken, command: exit 3}}
output: out
cluster: {{workers: 2}}
timeout: 120
""")
    r = sweep(spec)
    out = os.path.join(tmp, "out")
    if r.returncode != 1 or "[6/6]" not in r.stdout or "4 ok, 2 failed" not in r.stdout:
        fail(f"sweep: exit {r.returncode}\n{r.stdout}\n{r.stderr[-3000:]}")
    with open(os.path.join(out, "results.csv")) as f:
        rows = list(csv.DictReader(f))
    cells = [row["cell"] for row in rows]
    want = [f"servo_arm-s{s}-{p}" for s in (0, 1) for p in ("sine", "still", "broken")]
    if cells != want:
        fail(f"results rows {cells}, expected {want}")
    for row in rows:
        if row["policy"] == "broken":
            if row["status"] != "failed" or "policy exit 3" not in row["error"]:
                fail(f"the broken policy's row: {row}")
            continue
        # Lockstep from the start (--step-mode direct): exactly the policy's steps, recorded.
        if row["status"] != "ok" or abs(float(row["sim_time"]) - 0.5) > 0.021 or \
                int(row["frames"]) < 250:
            fail(f"row {row}")
        info = subprocess.run([URLAB, "replay", row["recording"], "--info"], capture_output=True,
                              text=True, timeout=60)
        if info.returncode != 0:
            fail(f"replay --info {row['recording']}: {info.stdout}{info.stderr}")
        if float(row["policy_final_time"]) < 0.5 or int(row["policy_steps"]) < 25:
            fail(f"the policy did not drive the cell: {row}")
    returns = {row["cell"]: float(row["policy_return"]) for row in rows if row["status"] == "ok"}
    if returns["servo_arm-s0-sine"] == returns["servo_arm-s0-still"] or \
            returns["servo_arm-s0-sine"] == returns["servo_arm-s1-sine"]:
        fail(f"the policy or the seed made no difference: {returns}")
    print("\n".join(r.stdout.strip().splitlines()[-3:]))

    # The same grid again: the same seed and policy, the same episode.
    again = sweep(spec, "--output", os.path.join(tmp, "again"))
    with open(os.path.join(tmp, "again", "results.csv")) as f:
        returns2 = {row["cell"]: float(row["policy_return"]) for row in csv.DictReader(f)
                    if row["status"] == "ok"}
    if again.returncode != 1 or returns2 != returns:
        fail(f"a second sweep: exit {again.returncode}, returns {returns2} vs {returns}")
    print(f"returns repeat exactly: {returns}")

    h = subprocess.run([URLAB, "sweep", "--help"], capture_output=True, text=True, timeout=60)
    if h.returncode != 0 or "policy command" not in h.stdout or "--scheduler" not in h.stdout:
        fail(f"sweep --help: {h.returncode}\n{h.stdout}{h.stderr}")
    bad = os.path.join(tmp, "bad.yaml")
    with open(bad, "w") as f:
        f.write("scenes: []\nseeds: [0]\nduration: 1\npolicies: []\nworkers: 3\n")
    b = sweep(bad)
    if b.returncode != 1 or f"{bad}:5: unknown key 'workers'" not in b.stderr:
        fail(f"a bad sweep file: {b.returncode}\n{b.stderr}")
    print("PASS")


if __name__ == "__main__":
    main()
