#!/usr/bin/python3
"""End to end: `urlab run` on loopback with ephemeral ports, driven by the Python client.

The client discovers the arm's actuators, sends a PD target for the shoulder by name, reads the
joint back from the streaming topics until it arrives, and leaves the process to stop cleanly.
Usage: python_client_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import signal
import subprocess
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient, StreamClient, UrlabEnv, UrlabError  # noqa: E402
from urlab_process import arm_scene, fail, start_urlab  # noqa: E402


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_py_")
    scene = arm_scene(tmp, ephemeral_ports=True, extra="""launchers:
  - {name: cannon, pos: [1.5, 1.5, 0.8], speed: 3}
""")
    files = os.path.join(tmp, "files")
    proc, endpoints = start_urlab(URLAB, scene, "--files-dir", files)
    try:
        with StreamClient(state=endpoints[0], control=endpoints[1], info=endpoints[2]) as client:
            robots = client.discover(timeout=10, expect=["arm"])
            arm = robots["arm"]
            assert arm.actuator_names == ["shoulder_motor", "elbow_motor"], arm
            end = time.monotonic() + 15
            q = None
            while time.monotonic() < end:
                client.send_control("arm", {"shoulder_motor": 0.5, "elbow_motor": -0.3})
                client.poll(timeout=0.05)
                q = client.joint_position("arm", "shoulder")
                e = client.joint_position("arm", "elbow")
                if q is not None and abs(q - 0.5) < 0.05 and abs(e + 0.3) < 0.05:
                    break
            else:
                fail(f"shoulder did not reach 0.5 (last {q})", proc)
            sensors = client.state["arm"]["sensor"]
            assert abs(sensors["shoulder_pos"][0] - q) < 0.05, sensors
            assert len(sensors["tip_pos"]) == 3, sensors
            print(f"shoulder reached {q:.3f}, elbow {e:.3f}; sensors {sorted(sensors)}")
        # Lockstep through the step server: exact step counts, the PD target reached.
        env = UrlabEnv("arm", endpoint=endpoints[3], frame_skip=5)
        obs, _ = env.reset()
        assert set(obs) >= {"qpos", "qvel", "ctrl", "act", "sensors"}, obs.keys()
        step0 = None
        for i in range(300):
            obs, _, _, _, info = env.step([-0.4, 0.6])
            if step0 is None:
                step0 = info["step"]
            elif info["step"] != step0 + 5 * i:
                fail(f"lockstep step {i}: step {info['step']}, expected {step0 + 5 * i}", proc)
        if abs(obs["qpos"][0] + 0.4) > 0.05 or abs(obs["qpos"][1] - 0.6) > 0.05:
            fail(f"lockstep PD targets not reached: {obs['qpos']}", proc)
        try:
            env.client.step(controls={"arm": [1.0]})  # one value for two actuators
            fail("dim_mismatch not reported", proc)
        except UrlabError as e:
            assert e.code == "dim_mismatch", e
        env.close()
        print(f"lockstep: 300 requests of 5 steps, qpos {obs['qpos']}")
        # Puppet mode, contacts and the model with its assets.
        with StepClient(endpoints[3]) as c:
            c.set_mode("puppet")
            r = c.puppet(per_articulation={"arm": {"qpos": [0.2, -0.1], "qvel": [0, 0]}})
            got = r["per_articulation"]["arm"]["qpos"]
            if abs(got[0] - 0.2) > 1e-12 or abs(got[1] + 0.1) > 1e-12:
                fail(f"puppet qpos not written: {got}", proc)
            try:
                c.puppet(per_articulation={"arm": {"qpos": [0.2]}})
                fail("puppet dim_mismatch not reported", proc)
            except UrlabError as e:
                assert e.code == "dim_mismatch", e
            contacts = c.get_contacts(max_contacts=8)
            assert contacts["count"] == len(contacts["contacts"]), contacts
            folder = tempfile.mkdtemp(prefix="urlab_assets_")
            path = c.model_with_assets(folder)
            with open(path) as f:
                text = f.read()
            if "<mujoco" not in text or tmp in text:
                fail(f"model_with_assets wrote {path} without a self-contained model", proc)
            print(f"puppet qpos {list(got)}, {contacts['count']} contact(s), "
                  f"model with {len(os.listdir(folder)) - 1} asset file(s)")
        with StepClient(endpoints[3]) as c:  # the puppeteer left: live again
            if c.info["mode"] != "live":
                fail(f"mode after the driver left: {c.info['mode']}", proc)
            # Recording, snapshots and replay through the server's recorder.
            rec = os.path.join(files, "run.urrec")
            if c.recording_start("run.urrec") != rec:
                fail("recording_start did not echo the path", proc)
            try:
                c.recording_start("run.urrec")
                fail("recording_already_active not reported", proc)
            except UrlabError as e:
                assert e.code == "recording_already_active", e
            deadline = time.monotonic() + 10
            while c.recording_status()["duration"] < 0.2 and time.monotonic() < deadline:
                time.sleep(0.02)
            done = c.recording_stop()
            if done["path"] != rec or done["frames"] < 50 or not os.path.exists(rec):
                fail(f"recording_stop: {done}", proc)
            t = c.snapshot_save("state.urrec")
            if c.snapshot_load("state.urrec") != t:
                fail("snapshot_load did not restore the saved time", proc)
            loaded = c.replay_load("run.urrec")
            assert loaded["session"] in [s["session"] for s in c.replay_list_sessions()], loaded
            c.replay_start(mode="kinematic")
            c.replay_stop()
            print(f"recorded {done['frames']} steps ({done['bytes']} bytes), snapshot at t={t}")
            # Impulse launchers: round robin over the pool, unknown names refused.
            shots = [c.fire_launcher("cannon")["projectile"] for _ in range(2)]
            if shots != [0, 1]:
                fail(f"fire_launcher projectiles {shots}, expected [0, 1]", proc)
            try:
                c.fire_launcher("nope")
                fail("unknown_launcher not reported", proc)
            except UrlabError as e:
                assert e.code == "unknown_launcher", e
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            fail("urlab did not stop on SIGINT", proc)
    if proc.returncode not in (0, 130):
        fail(f"urlab exited with {proc.returncode}")
    if "summary:" not in out:
        fail("no summary line")
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
