"""Starting `urlab run` for the Python end-to-end tests: the process, and the network endpoints
its log names (ephemeral ports), or a failure with its log."""
import re
import subprocess
import sys
import time


def fail(message, proc=None):
    """Prints FAIL and exits 1; kills `proc` first and shows its log."""
    if proc:
        proc.kill()
        print(proc.stderr.read() if proc.stderr else "", file=sys.stderr)
    print("FAIL:", message)
    sys.exit(1)


def start_urlab(urlab, scene, *extra, timeout=30):
    """Runs `urlab run SCENE --duration 60 EXTRA...`; returns (process, (state, control, info,
    rpc)) once its log names the bound endpoints."""
    proc = subprocess.Popen([urlab, "run", scene, "--duration", "60", *extra],
                            stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            fail("urlab exited before serving the network", proc)
        m = re.search(r"network: state (\S+) \| control (\S+) \| info (\S+) \| rpc (\S+)", line)
        if m:
            return proc, m.groups()
    fail("no network line in urlab's log", proc)


def start_announced(urlab, scene, *extra, timeout=60, announce=None):
    """Runs `urlab run SCENE --ports auto --announce FILE --duration 120 EXTRA...`; returns
    (process, announce dict) once the file appears (the system chose every port)."""
    import json
    import os
    import tempfile
    if announce is None:
        fd, announce = tempfile.mkstemp(prefix="urlab_announce_", suffix=".json")
        os.close(fd)
        os.unlink(announce)
    proc = subprocess.Popen([urlab, "run", scene, "--ports", "auto", "--announce", announce,
                             "--duration", "120", *extra],
                            stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if os.path.exists(announce):
            with open(announce) as f:
                return proc, json.load(f)
        if proc.poll() is not None:
            fail(f"urlab exited ({proc.returncode}) before announcing", proc)
        time.sleep(0.05)
    fail(f"no announce file after {timeout} s", proc)
