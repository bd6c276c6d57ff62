#!/usr/bin/python3
"""Issue 38, case 5: `urlab run --announce FILE` removes only what this run wrote, and never
blocks on the announce file.

1. Two runs announce in one file: the second's file replaces the first's; when the first ends it
   leaves the second's (it used to remove it by name).
2. A file that is there already and is not an announce file (the user's): refused before
   anything runs (exit 1, naming the file); the file is untouched (it used to be overwritten,
   then deleted).
3. A symbolic link: the file it points to gets the JSON, and at the end loses it (removed); the
   link is the user's and stays (the link used to be removed, leaving the target's stale JSON).
4. A FIFO nobody reads: the run does not wait for a reader (it used to block after binding); it
   plays, says it could not announce, and ends as asked.
Usage: announce_e2e.py URLAB_BINARY SOURCE_DIR
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_process import arm_scene  # noqa: E402

PROCS = []


def fail(message):
    for p in PROCS:
        if p.poll() is None:
            p.kill()
    print("FAIL:", message)
    sys.exit(1)


def start(scene, announce, *extra):
    p = subprocess.Popen([URLAB, "run", scene, "--ports", "auto", "--announce", announce,
                          "--no-cameras", *extra], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    PROCS.append(p)
    return p


def announced_by(path, proc, timeout=60):
    """The announce file's JSON once it names `proc`."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with open(path) as f:
                a = json.load(f)
            if a.get("pid") == proc.pid:
                return a
        except (OSError, ValueError):
            pass
        if proc.poll() is not None:
            fail(f"urlab exited ({proc.returncode}) before announcing:\n{proc.stderr.read()}")
        time.sleep(0.05)
    fail(f"{path} never named pid {proc.pid}")


def stop(proc):
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        fail("a run did not stop within 30 s of SIGINT")
    return proc.returncode, err


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_announce_")
    scene = arm_scene(tmp, "arm.yaml", ephemeral_ports=True)

    # 1. Two runs, one announce file.
    shared = os.path.join(tmp, "shared.json")
    first = start(scene, shared, "--duration", "120")
    announced_by(shared, first)
    second = start(scene, shared, "--duration", "120")
    announced_by(shared, second)
    stop(first)
    try:
        with open(shared) as f:
            still = json.load(f)
    except OSError:
        fail("the first run removed the second run's live announce file")
    if still.get("pid") != second.pid:
        fail(f"the announce file names {still.get('pid')}, not the live run {second.pid}")
    stop(second)
    if os.path.exists(shared):
        fail("the second run left its announce file")
    print("two runs, one file: the first leaves the second's")

    # 2. The user's file.
    precious = os.path.join(tmp, "notes.json")
    with open(precious, "w") as f:
        f.write("my notes\n")
    r = subprocess.run([URLAB, "run", scene, "--ports", "auto", "--announce", precious,
                        "--duration", "0.2", "--no-cameras"], capture_output=True, text=True,
                       timeout=60)
    with open(precious) as f:
        kept = f.read()
    if kept != "my notes\n":
        fail(f"the user's file became {kept!r} (exit {r.returncode})")
    if r.returncode != 1 or precious not in r.stderr:
        fail(f"a file that is not an announce file: exit {r.returncode}:\n{r.stderr}")
    print("the user's file: refused, untouched:", r.stderr.strip().splitlines()[-1])

    # 3. A symbolic link.
    target = os.path.join(tmp, "target.json")
    link = os.path.join(tmp, "link.json")
    os.symlink(target, link)
    run = start(scene, link, "--duration", "120")
    announced_by(target, run)
    if not os.path.islink(link):
        fail("the link was replaced by a file")
    stop(run)
    if not os.path.islink(link):
        fail("the run removed the user's link")
    if os.path.exists(target):
        fail("the link's target still announces a run that ended")
    print("a symbolic link: written through, its target removed at the end, the link kept")

    # 4. A FIFO nobody reads.
    fifo = os.path.join(tmp, "fifo.json")
    os.mkfifo(fifo)
    began = time.monotonic()
    p = start(scene, fifo, "--duration", "1")
    try:
        out, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        fail("a FIFO with no reader blocked the run")
    if p.returncode != 0 or "summary:" not in out:
        fail(f"a FIFO with no reader: exit {p.returncode}:\n{err}")
    if "no reader" not in err:
        fail(f"the run did not say that nobody read the FIFO:\n{err}")
    if not os.path.exists(fifo) or not os.path.stat.S_ISFIFO(os.stat(fifo).st_mode):
        fail("the FIFO was replaced or removed")
    print(f"a FIFO with no reader: not waited for ({time.monotonic() - began:.1f} s)")
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
