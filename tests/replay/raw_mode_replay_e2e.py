#!/usr/bin/python3
"""End to end: steps taken with `control_mode: raw` are recorded as raw and replay bit for bit.

A `urlab run` of the servo arm under its PD controller (system-chosen ports), in lockstep
(direct mode), recorded through the step server: steps whose values are the PD's targets, then
steps in `control_mode: raw` (the values are the actuators' controls as they are: the
controller does not run), then targets again. Shown:
- the replies show the raw values as the controls in raw mode only;
- `urlab replay FILE --info` counts the recorded steps that ran in raw mode;
- `urlab replay FILE --check` (re-simulation of every step) reports the run identical;
Usage: raw_mode_replay_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import struct
import subprocess
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient  # noqa: E402
from urlab_process import arm_scene, fail, start_announced  # noqa: E402

PHASES = (("controller", 40), ("raw", 40), ("controller", 40))


def numbers(v):
    """A numeric vector of a reply: a list, or packed little-endian f64 bytes."""
    if isinstance(v, (bytes, bytearray)):
        return list(struct.unpack(f"<{len(v) // 8}d", v))
    return [float(x) for x in v]


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_raw_replay_")
    scene = arm_scene(tmp)
    proc, a = start_announced(URLAB, scene, "--no-cameras", "--files-dir", tmp,
                              "--step-mode", "direct")
    modes = []
    try:
        with StepClient(a["endpoints"]["rpc"]) as c:
            c.reset()
            nu = len(numbers(c.step(1)["per_articulation"]["arm"]["ctrl"]))
            c.recording_start("raw.urrec")
            for mode, steps in PHASES:
                for i in range(steps):
                    values = [0.3 * ((k + i) % 3 - 1) for k in range(nu)]
                    r = c.call("step", n_steps=1,
                               per_articulation={"arm": {"ctrl": values, "control_mode": mode}})
                    ctrl = numbers(r["per_articulation"]["arm"]["ctrl"])
                    if (ctrl == values) != (mode == "raw"):
                        fail(f"{mode} step {i}: ctrl {ctrl} for values {values}", proc)
                    modes.append(mode)
            done = c.recording_stop()
            saved = done["path"]
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    if done["frames"] < len(modes):
        fail(f"recorded {done['frames']} steps, stepped {len(modes)}")

    r = subprocess.run([URLAB, "replay", saved, "--check"], capture_output=True, text=True,
                       timeout=300)
    print(r.stdout.strip())
    if r.returncode != 0 or "identical" not in r.stdout:
        fail(f"replay --check of the raw run: exit {r.returncode}\n{r.stdout}{r.stderr}")

    info = subprocess.run([URLAB, "replay", saved, "--info"], capture_output=True, text=True,
                          timeout=120)
    if info.returncode != 0:
        fail(f"replay --info: exit {info.returncode}\n{info.stdout}{info.stderr}")
    raw_steps = sum(1 for m in modes if m == "raw")
    line = next((x for x in info.stdout.splitlines() if x.startswith("raw control:")), "")
    if f"arm {raw_steps} steps" not in line:
        fail(f"replay --info does not count {raw_steps} raw steps: {line!r}\n{info.stdout}")

    print(f"recorded {done['frames']} steps, {raw_steps} raw; replay --check identical")
    print("PASS")


if __name__ == "__main__":
    main()
