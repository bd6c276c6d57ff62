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
