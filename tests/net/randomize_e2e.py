#!/usr/bin/python3
"""End to end: domain randomisation through the step server of a real `urlab run --seed`
(system-chosen ports), in lockstep (direct mode).

A pendulum arm whose scene randomises friction, mass, damping, actuator gain, gravity and the
initial joint positions:
- every `reset` reply carries the values drawn (`randomized`); `reset {seed}` twice draws the same
  values and, with the same controls, gives the same trajectory bit for bit; another seed draws
  other values;
- `reset {randomize}` replaces the scene's section for that reset; unknown targets are refused;
- a randomised run recorded through the step server replays bit for bit (`urlab replay
  --check`), and a randomised reset while recording is refused (`recording_active`).
Usage: randomize_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient, UrlabError  # noqa: E402
from urlab_process import fail, start_announced  # noqa: E402

ARM = """<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" gear="1" ctrllimited="true" ctrlrange="-100 100"/>
  </actuator>
</mujoco>
"""

SCENE = """articulations:
  - name: arm
    mjcf: arm.xml
randomize:
  gravity:
    z: {uniform: [-0.5, 0.5]}
  arm:
    friction: {uniform: [0.5, 1.5]}
    mass: {log_uniform: [0.5, 2]}
    damping: {normal: [1, 0.2]}
    gain: {uniform: [0.8, 1.2]}
    qpos_noise: {normal: [0, 0.1]}
"""


def run(c, steps=150):
    q = []
    for i in range(steps):
        r = c.step(1, controls={"arm": [0.3 * (i % 7)]})
        q.append(float(r["per_articulation"]["arm"]["qpos"][0]))
    return q


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_randomize_")
    with open(os.path.join(tmp, "arm.xml"), "w") as f:
        f.write(ARM)
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "w") as f:
        f.write(SCENE)
    proc, a = start_announced(URLAB, scene, "--no-cameras", "--files-dir", tmp,
                              "--step-mode", "direct", "--seed", "17")
    try:
        with StepClient(a["endpoints"]["rpc"]) as c:
            plain = c.call("reset")
            if "randomized" not in plain or set(plain["randomized"]["arm"]) != {
                    "friction", "mass", "damping", "gain", "qpos_noise.hinge"}:
                fail(f"reset without a seed: {plain.get('randomized')}", proc)
            first = c.call("reset", seed=123)["randomized"]
            t1 = run(c)
            second = c.call("reset", seed=123)["randomized"]
            t2 = run(c)
            if first != second or first["seed"] != 123:
                fail(f"the same seed drew {first} and {second}", proc)
            if t1 != t2:
                fail("the same seed gave two trajectories", proc)
            other = c.call("reset", seed=124)["randomized"]
            if other["arm"] == first["arm"]:
                fail("seeds 123 and 124 drew the same values", proc)
            print(f"seed 123 drew {first}")

            override = c.call("reset", seed=5, randomize={"arm": {"friction": {"uniform": [2, 2]}}})
            if override["randomized"]["arm"] != {"friction": 2.0}:
                fail(f"the request's randomize did not replace the scene's: {override}", proc)
            try:
                c.call("reset", randomize={"robot": {"friction": {"uniform": [0, 1]}}})
                fail("an unknown target was accepted", proc)
            except UrlabError as e:
                if e.code != "bad_value":
                    fail(f"unknown target: {e.code}", proc)

            # A randomised run, recorded after its reset, replays bit for bit.
            c.call("reset", seed=99)
            rec = c.recording_start("randomized.urrec")
            run(c, 300)
            try:
                c.call("reset", seed=100)
                fail("a randomised reset while recording was accepted", proc)
            except UrlabError as e:
                if e.code != "recording_active":
                    fail(f"reset while recording: {e.code} {e}", proc)
            done = c.recording_stop()
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    r = subprocess.run([URLAB, "replay", rec, "--check"], capture_output=True, text=True,
                       timeout=300)
    print(r.stdout.strip())
    if r.returncode != 0 or "identical" not in r.stdout:
        fail(f"replay --check of the randomised run: exit {r.returncode}\n{r.stdout}{r.stderr}")
    print(f"recorded {done['frames']} steps of a randomised run; replay --check: identical")
    print("PASS")


if __name__ == "__main__":
    main()
