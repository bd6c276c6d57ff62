#!/usr/bin/python3
"""End to end: `urlab run` streams two cameras of tests/data/cameras/rig.xml; the Python client
discovers them, receives numpy frames from both (RGB, depth, segmentation), checks what the top
camera sees (the red box 1.9 m away, its geom id), and through the step server gets frames with
include_cameras: "sync" frames show exactly the step of the reply, and with set_camera_delay the
state that many steps before.
Usage: python_camera_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
import numpy as np  # noqa: E402
from urlab_process import camera_rig_scene, fail, start_urlab  # noqa: E402
from urlab_client import CameraClient, StepClient, StreamClient  # noqa: E402


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_cam_")
    scene = camera_rig_scene(tmp, "  streams:\n    rig/top: {modes: [rgb, depth, segmentation]}\n")
    proc, endpoints = start_urlab(URLAB, scene, "--ports", "auto")  # cameras' ports too
    try:
        with StreamClient(state=endpoints[0], control=endpoints[1], info=endpoints[2]) as client:
            robots = client.discover(timeout=10, expect=["rig"])
        cams = {c["name"]: c for c in robots["rig"].cameras}
        if sorted(cams) != ["top", "top/depth", "top/segmentation", "wrist"]:
            fail(f"camera_list: {sorted(cams)}", proc)
        for c in cams.values():
            assert c["width"] == 64 and c["height"] == 48 and c["endpoint"], c
        seg_names = {e["id"]: e["name"] for e in cams["top/segmentation"]["ids"]}
        box = [i for i, n in seg_names.items() if n == "rig_box"][0]

        # Streaming: frames from both cameras, as numpy arrays.
        clients = {n: CameraClient(c) for n, c in cams.items()}
        frames = {}
        latencies = []
        for name, cam in clients.items():
            for _ in range(5):  # the first frames; keep the last with its meta
                image, meta = cam.receive(timeout=10)
                if meta is not None:
                    latencies.append((meta["received_ns"] - meta["state_wall_ns"]) / 1e6)
            frames[name] = (image, meta)
        rgb = frames["top"][0]
        assert rgb.shape == (48, 64, 3) and rgb.dtype == np.uint8, rgb.shape
        r, g, b = (int(v) for v in rgb[24, 32])
        if not (r > 150 and g < 40 and b < 40):
            fail(f"top camera centre is not the red box: {rgb[24, 32]}", proc)
        depth = frames["top/depth"][0]
        assert depth.shape == (48, 64) and depth.dtype == np.float32, depth.dtype
        if abs(float(depth[24, 32]) - 1.9) > 1e-3:
            fail(f"top camera centre depth {depth[24, 32]}, expected 1.9", proc)
        ids = frames["top/segmentation"][0]
        assert ids.shape == (48, 64) and ids.dtype == np.int32, ids.dtype
        if ids[24, 32] != box:
            fail(f"segmentation centre id {ids[24, 32]}, expected {box} (rig_box)", proc)
        wrist = frames["wrist"][0]
        assert wrist.shape == (48, 64, 3), wrist.shape
        meta = frames["wrist"][1]
        assert meta is None or meta["width"] == 64, meta
        print(f"streamed frames from 2 cameras (4 streams); box id {box}; latency ms "
              f"{sorted(latencies)[len(latencies) // 2]:.1f} median of {len(latencies)}")
        for cam in clients.values():
            cam.close()

        # The step server: "sync" frames show the reply's own step, "latest" the newest.
        with StepClient(endpoints[3]) as sim:
            topics = {c["name"] for c in sim.info["articulations"][0]["camera_topics"]}
            assert topics == set(cams), topics
            sim.set_mode("direct")
            for i in range(10):
                reply = sim.step(n_steps=7, include_cameras={"top": "sync", "wrist": "latest",
                                                             "top/depth": "sync"})
                top = reply["cameras"]["rig"]["top"]
                if top.get("step") != reply["step"]:
                    fail(f"sync frame shows step {top.get('step')}, reply step {reply['step']}",
                         proc)
                assert reply["cameras"]["rig"]["top/depth"]["step"] == reply["step"]
                assert top["image"].shape == (48, 64, 3)
                assert "image" in reply["cameras"]["rig"]["wrist"]
            reply = sim.step(n_steps=1, include_cameras=True)
            assert set(reply["cameras"]["rig"]) == set(cams), reply["cameras"].keys()
            try:
                sim.step(include_cameras={"nose": "sync"})
                fail("unknown camera accepted", proc)
            except Exception as e:  # UrlabError
                assert "nose" in str(e), e
            # An emulated camera delay of 3 steps: sync frames show the state 3 steps before the
            # reply's, from the camera's topic too.
            ok = sim.call("set_camera_delay", cameras={"top": {"delay_steps": 3}})
            assert ok["cameras"]["rig/top"]["delay_steps"] == 3, ok
            seen = []
            for i in range(8):
                reply = sim.step(n_steps=1, include_cameras={"top": "sync"})
                top = reply["cameras"]["rig"]["top"]
                seen.append(reply["step"] - top["step"] if "step" in top else None)
            if seen[3:] != [3] * 5:
                fail(f"delayed camera: reply step - frame step over 8 steps: {seen}", proc)
            try:
                sim.call("set_camera_delay", cameras={"nose": {"delay_steps": 1}})
                fail("a delay for an unknown camera was accepted", proc)
            except Exception as e:  # UrlabError unknown_camera
                assert "nose" in str(e), e
            sim.call("set_camera_delay", cameras={"rig/top": {}})
            reply = sim.step(n_steps=1, include_cameras={"top": "sync"})
            assert reply["cameras"]["rig"]["top"]["step"] == reply["step"], reply["cameras"]
        print(f"step server: 10 sync steps, camera_meta step == step (last {reply['step']}); "
              f"a 3-step camera delay seen as {seen}")
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            fail("urlab did not stop", proc)
    if proc.returncode not in (0, 143, 128 + 15):
        fail(f"urlab exit code {proc.returncode}", proc)
    print("PASS")


if __name__ == "__main__":
    main()
