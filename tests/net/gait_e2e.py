#!/usr/bin/python3
"""End to end: `set_twist` walks a quadruped through the step server of a real `urlab run`.

For the bundled quadruped (examples/scenes/quadruped_walk.yaml) and the Go2-style dog of
examples/scenes/go2_network.yaml as shipped (only loopback ports with ephemeral numbers added),
in lockstep (direct mode, so the run is deterministic): after 0.5 s standing, 5 s at vx = 0.5 m/s
must carry the base at least 1 m forward, and after a reset 5 s at 0.5 rad/s must turn it at least
60 degrees, with the base height within 75..125 % of its standing height and never tipped.
Usage: gait_e2e.py URLAB_BINARY SOURCE_DIR
"""
import math
import os
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient  # noqa: E402
from urlab_process import fail, start_urlab  # noqa: E402

DT = 0.002  # both models' timestep
CHUNK = 10  # steps per request


def base_pose(reply):
    """(x, y, z, yaw, up): the free joint's position, heading and the z of the base's z axis."""
    q = reply["per_articulation"]["dog"]["qpos"]
    w, x, y, z = q[3], q[4], q[5], q[6]
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    up = 1 - 2 * (x * x + y * y)
    return q[0], q[1], q[2], yaw, up


def walk(client, vx, yaw_rate, seconds=5.0):
    """Standing 0.5 s, then `seconds` at the twist; returns the figures of the walk."""
    reply = client.step(int(0.5 / DT))
    x0, y0, stand, yaw0, _ = base_pose(reply)
    applied = client.set_twist("dog", vx=vx, yaw_rate=yaw_rate)
    assert applied["linear"][0] == vx and applied["angular"][2] == yaw_rate, applied
    low, high, upright, turned, last = stand, stand, 1.0, 0.0, yaw0
    for _ in range(int(seconds / DT) // CHUNK):
        x, y, z, yaw, up = base_pose(client.step(CHUNK))
        turned += math.remainder(yaw - last, 2 * math.pi)
        last = yaw
        low, high, upright = min(low, z), max(high, z), min(upright, up)
    forward = math.cos(yaw0) * (x - x0) + math.sin(yaw0) * (y - y0)
    return {"forward": forward, "yaw_deg": math.degrees(turned), "stand": stand, "low": low,
            "high": high, "upright": upright}


def check(name, kind, r, proc):
    print(f"{name} {kind}: forward {r['forward']:.3f} m, yaw {r['yaw_deg']:.1f} deg, base height "
          f"{r['low']:.3f}..{r['high']:.3f} m (standing {r['stand']:.3f}), upright >= "
          f"{r['upright']:.3f}")
    if not (0.75 * r["stand"] < r["low"] and r["high"] < 1.25 * r["stand"]):
        fail(f"{name} {kind}: the base left its standing range", proc)
    if r["upright"] < 0.9:
        fail(f"{name} {kind}: the base tipped", proc)


def run(scene_file, name):
    tmp = tempfile.mkdtemp(prefix="urlab_gait_")
    with open(scene_file) as f:
        text = f.read().replace("../../tests", os.path.join(SOURCE, "tests"))
        text = text.replace("../models", os.path.join(SOURCE, "examples", "models"))
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "w") as f:
        f.write(text + """network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "tcp://127.0.0.1:*"
""")
    proc, endpoints = start_urlab(URLAB, scene)
    try:
        with StepClient(endpoints[3]) as client:
            client.set_mode("direct")
            forward = walk(client, 0.5, 0.0)
            check(name, "vx 0.5 m/s", forward, proc)
            if forward["forward"] < 1.0:
                fail(f"{name}: walked {forward['forward']:.3f} m in 5 s at 0.5 m/s", proc)
            client.reset()
            turn = walk(client, 0.0, 0.5)
            check(name, "yaw 0.5 rad/s", turn, proc)
            if turn["yaw_deg"] < 60:
                fail(f"{name}: turned {turn['yaw_deg']:.1f} deg in 5 s at 0.5 rad/s", proc)
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def main():
    scenes = os.path.join(SOURCE, "examples", "scenes")
    run(os.path.join(scenes, "quadruped_walk.yaml"), "quadruped")
    run(os.path.join(scenes, "go2_network.yaml"), "go2")
    print("PASS")


if __name__ == "__main__":
    main()
