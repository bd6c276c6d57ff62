#!/usr/bin/python3
"""End to end: emulated latency through the step server of a real `urlab run` (system-chosen
ports), in lockstep (direct mode).

A pendulum arm with a motor, the scene's `latency:` giving a control delay of 3 steps with a
jitter of +-1 step and an observation delay of 4 steps, seed 5:
- the ctrl each step's reply shows (the control applied) is the one sent 2..4 steps earlier,
  never reordered, and every lag of the stated distribution occurs;
- with the observation delay set to 0 over `set_latency`, then back to 4 steps, the same
  controls after a reset give replies whose qpos is exactly the undelayed qpos 4 steps earlier;
- the same seed gives the same trajectory (a second reset, bit for bit), another seed
  (`set_latency seed`) another one;
- `get_latency` echoes the settings, a bad setting is refused with bad_value;
- the delayed run recorded through the step server replays bit for bit (`urlab replay --check`).
Usage: latency_e2e.py URLAB_BINARY SOURCE_DIR
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
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.01"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" gear="1" ctrllimited="true" ctrlrange="-1000 1000"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
</mujoco>
"""

SCENE = """seed: 5
articulations:
  - name: arm
    mjcf: arm.xml
    latency:
      control: {delay_steps: 3, jitter_steps: 1}
      observation: {delay_steps: 4}
"""

STEPS = 200


def control(i):
    return 0.5 + 0.001 * i  # distinct per step, small enough to keep the arm swinging gently


def drive(c):
    """Steps STEPS times, one step per request, sending control(i) before step i; returns
    (applied ctrl per step, qpos per step, sensor per step)."""
    applied, qpos, sensor = [], [], []
    for i in range(STEPS):
        r = c.step(1, controls={"arm": [control(i)]})
        a = r["per_articulation"]["arm"]
        applied.append(float(a["ctrl"][0]))
        qpos.append(float(a["qpos"][0]))
        sensor.append(float(a["sensors"]["angle"][0]))
    return applied, qpos, sensor


def reset(c):
    """Resets with the command in effect being 0 (what a delayed line holds until the first
    delayed command arrives), as at the start: every episode starts alike."""
    c.step(1, controls={"arm": [0.0]})
    c.reset()


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_latency_")
    with open(os.path.join(tmp, "arm.xml"), "w") as f:
        f.write(ARM)
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "w") as f:
        f.write(SCENE)
    proc, a = start_announced(URLAB, scene, "--no-cameras", "--files-dir", tmp,
                              "--step-mode", "direct")
    try:
        with StepClient(a["endpoints"]["rpc"]) as c:
            got = c.call("get_latency", articulation="arm")
            if got["control"] != {"delay_steps": 3, "jitter_steps": 1, "rate_hz": 0} or \
                    got["observation"]["delay_steps"] != 4 or got["seed"] != 5:
                fail(f"get_latency: {got}", proc)
            try:
                c.call("set_latency", articulation="arm", control={"delay_steps": 1.5})
                fail("a fractional step count was accepted", proc)
            except UrlabError as e:
                if e.code != "bad_value":
                    fail(f"bad setting: {e.code} {e}", proc)

            # 1. Control delay: the applied ctrl is the one sent 2..4 steps earlier.
            reset(c)
            rec = c.recording_start("delayed.urrec")
            applied, delayed_qpos, delayed_sensor = drive(c)
            done = c.recording_stop()
            lags = {}
            last = -1
            for i in range(10, STEPS):
                sent = round((applied[i] - 0.5) / 0.001)
                if applied[i] != control(sent):
                    fail(f"step {i}: applied ctrl {applied[i]} was never sent", proc)
                if sent < last:
                    fail(f"step {i}: controls reordered ({sent} after {last})", proc)
                last = sent
                lags[i - sent] = lags.get(i - sent, 0) + 1
            if set(lags) != {2, 3, 4}:
                fail(f"control lags {sorted(lags.items())}, want exactly 2, 3 and 4", proc)
            print(f"control lags (steps: count) {sorted(lags.items())}")

            # 2. Same seed, same trajectory: the reset restarts the delays with the same draws.
            reset(c)
            again = drive(c)
            if again != (applied, delayed_qpos, delayed_sensor):
                fail("the same seed gave another trajectory after a reset", proc)

            # 3. Observation delay: without it the same run shows the true state; with it, the
            # state 4 steps earlier.
            c.call("set_latency", articulation="arm", observation={})
            reset(c)
            _, true_qpos, true_sensor = drive(c)
            if true_qpos == delayed_qpos:
                fail("the observation delay changed nothing", proc)
            for i in range(4, STEPS):
                if delayed_qpos[i] != true_qpos[i - 4] or delayed_sensor[i] != true_sensor[i - 4]:
                    fail(f"step {i}: observed {delayed_qpos[i]}, true 4 steps earlier "
                         f"{true_qpos[i - 4]}", proc)
            print(f"observation delay: {STEPS - 4} steps each exactly 4 steps behind")

            # 4. Another seed, another trajectory.
            c.call("set_latency", articulation="arm", seed=6)
            reset(c)
            other = drive(c)
            if other[0] == applied:
                fail("seed 6 drew the same control delays as seed 5", proc)
    finally:
        proc.terminate()
        proc.wait(timeout=30)

    # 5. The delayed run, recorded, replays bit for bit.
    r = subprocess.run([URLAB, "replay", rec, "--check"], capture_output=True, text=True,
                       timeout=300)
    print(r.stdout.strip())
    if r.returncode != 0 or "identical" not in r.stdout:
        fail(f"replay --check of the delayed run: exit {r.returncode}\n{r.stdout}{r.stderr}")
    print(f"recorded {done['frames']} steps; replay --check: identical")
    print("PASS")


if __name__ == "__main__":
    main()
