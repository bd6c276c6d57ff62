#!/usr/bin/python3
"""End to end: the Python examples against `urlab run` of the Go2-style scene, ephemeral ports.

examples/python/pd_stand.py must make the robot lie down and stand up again over the streaming
topics (it exits non-zero unless the base rose by 5 cm); examples/python/rollout.py must collect
10,000 lockstep steps through the step server and save them; the file is then checked.
Usage: python_examples_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
EXAMPLES = os.path.join(SOURCE, "examples", "python")


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_examples_")
    scene = os.path.join(tmp, "go2.yaml")
    with open(os.path.join(SOURCE, "examples", "scenes", "go2_network.yaml")) as f:
        text = f.read().replace("../../tests", os.path.join(SOURCE, "tests"))
    with open(scene, "w") as f:  # the example scene, on ephemeral loopback ports
        f.write(text + """network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "tcp://127.0.0.1:*"
""")
    proc = subprocess.Popen([URLAB, "run", scene, "--duration", "120"], stderr=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, text=True)
    try:
        endpoints = None
        deadline = time.monotonic() + 30
        while endpoints is None and time.monotonic() < deadline:
            line = proc.stderr.readline()
            if not line:
                break
            m = re.search(r"network: state (\S+) \| control (\S+) \| info (\S+) \| rpc (\S+)", line)
            if m:
                endpoints = m.groups()
        if endpoints is None:
            print("FAIL: no network line in urlab's log")
            return 1
        stand = subprocess.run(
            [sys.executable, os.path.join(EXAMPLES, "pd_stand.py"), "--state", endpoints[0],
             "--control", endpoints[1], "--info", endpoints[2]],
            capture_output=True, text=True, timeout=60)
        print(stand.stdout, stand.stderr)
        if stand.returncode != 0:
            print("FAIL: pd_stand.py did not make the robot stand up again")
            return 1
        out = os.path.join(tmp, "rollout.npz")
        rollout = subprocess.run(
            [sys.executable, os.path.join(EXAMPLES, "rollout.py"), "--endpoint", endpoints[3],
             "--out", out], capture_output=True, text=True, timeout=300)
        print(rollout.stdout, rollout.stderr)
        if rollout.returncode != 0:
            print("FAIL: rollout.py failed")
            return 1
        data = np.load(out)
        if data["qpos"].shape != (10000, 19) or data["action"].shape != (10000, 12):
            print("FAIL: rollout shapes", {k: data[k].shape for k in data})
            return 1
        # Lockstep: the recorded times advance one timestep per step within an episode.
        dt = np.diff(data["time"][:2000])
        if not np.allclose(dt, 0.002):
            print("FAIL: lockstep times are not one step apart:", dt[:5])
            return 1
        print("PASS")
        return 0
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()


if __name__ == "__main__":
    sys.exit(main())
