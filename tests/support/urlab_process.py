"""Starting `urlab run` for the Python end-to-end tests: the process, and the network endpoints
its log names (ephemeral ports), or a failure with its log."""
import os
import re
import subprocess
import sys
import time

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SERVO_ARM = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")


def arm_scene(folder, name="scene.yaml", ephemeral_ports=False, extra="", controller=True):
    """Writes the Python tests' scene into `folder`: the bundled servo arm as articulation `arm`
    under a PD controller (kp 400, kv 20; none with controller=False: the actions are its raw
    controls), with `extra` YAML appended; with `ephemeral_ports` every socket binds a port the
    system chooses and the network is the control source. Returns the scene's path."""
    text = ""
    if ephemeral_ports:
        text += """control_source: network
network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "tcp://127.0.0.1:*"
"""
    text += f"""articulations:
  - name: arm
    mjcf: {SERVO_ARM}
""" + ("    controller: {type: pd, kp: 400, kv: 20}\n" if controller else "") + extra
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def camera_rig_scene(folder, extra=""):
    """Writes the camera tests' scene into `folder`: tests/data/cameras/rig.xml as articulation
    `rig` streaming every camera at 64x48, 30 Hz, every socket on a port the system chooses, with
    `extra` YAML appended (under `cameras:`, indented two spaces). Returns the scene's path."""
    model = os.path.join(SOURCE, "tests", "data", "cameras", "rig.xml")
    path = os.path.join(folder, "scene.yaml")
    with open(path, "w") as f:
        f.write(f"""network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "tcp://127.0.0.1:*"
articulations:
  - name: rig
    mjcf: {model}
    cameras: true
cameras:
  width: 64
  height: 48
  rate: 30
""" + extra)
    return path


# The servers a test started (its own helpers append them): check() kills them before failing,
# stop_all() ends them at the test's end.
PROCS = []


def check(cond, message):
    """Fails the test with `message` unless `cond`, killing every server in PROCS first."""
    if not cond:
        for p in PROCS:
            if p.poll() is None:
                p.kill()
        fail(message)


def raises(kind, text, fn):
    """Fails the test (check) unless fn() raises `kind` with `text` in its message."""
    try:
        fn()
    except kind as e:
        check(text in str(e), f"expected {text!r} in {e!r}")
        return
    check(False, f"no {kind.__name__} ({text!r})")


def stop_all():
    """Terminates every server in PROCS and waits for it (a test's end)."""
    for p in PROCS:
        p.terminate()
        p.wait(timeout=30)


def wave_actions(t, n, nu):
    """(n, nu) actions for step t: different per environment and per step, the same in every
    run (the batched tests compare runs bit for bit)."""
    import numpy as np
    i = np.arange(n)[:, None]
    j = np.arange(nu)[None, :]
    return np.sin(0.7 * t + 0.3 * i + 1.1 * j)


def fail(message, proc=None):
    """Prints FAIL and exits 1; kills `proc` first and shows its log."""
    if proc:
        proc.kill()
        print(proc.stderr.read() if proc.stderr else "", file=sys.stderr)
    print("FAIL:", message)
    sys.exit(1)


def start_urlab(urlab, scene, *extra, timeout=30, duration=60):
    """Runs `urlab run SCENE --duration DURATION EXTRA...` (simulated seconds: exactly that many
    steps, a client's lockstep steps included); returns (process, (state, control, info, rpc))
    once its log names the bound endpoints."""
    proc = subprocess.Popen([urlab, "run", scene, "--duration", str(duration), *extra],
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


def start_announced(urlab, scene, *extra, timeout=60, announce=None, duration=120):
    """Runs `urlab run SCENE --ports auto --announce FILE --duration DURATION EXTRA...`; returns
    (process, announce dict) once the file appears (the system chose every port). DURATION is
    simulated seconds: a server left playing live with --max-speed goes through 120 of them in a
    second or two, so a test that leaves one so between its uses gives a longer one."""
    import json
    import os
    import tempfile
    if announce is None:
        fd, announce = tempfile.mkstemp(prefix="urlab_announce_", suffix=".json")
        os.close(fd)
        os.unlink(announce)
    proc = subprocess.Popen([urlab, "run", scene, "--ports", "auto", "--announce", announce,
                             "--duration", str(duration), *extra],
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
