#!/usr/bin/python3
"""End to end: camera frames for a 2026 client (hello client_version "urlab_bridge/...") from
`urlab run` of tests/data/cameras/rig.xml, written from docs/protocol.md alone (plain zmq and
msgpack):
- hello's camera_topics is a map {stream: {mode, resolution, fovy, zmq_endpoint, zmq_topic}};
- frames on zmq_topic start with the 32-byte header (magic UCM1, header size, frame id,
  simulation time, step), then exactly width*height pixels (4 bytes each); frame ids increase;
- in stepped mode a frame whose header's sim_time is the time a step reply showed arrives after
  that step (a client can tell it from an older one);
- set_camera_streaming {camera: false} stops a camera's frames, true starts them again; an
  unknown camera is unknown_camera;
- subscribers of the bare topic still get bare pixels.
Usage: upstream2026_camera_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import struct
import subprocess
import sys
import tempfile
import time

import msgpack
import zmq

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_process import camera_rig_scene, fail, start_urlab  # noqa: E402

PROC = None


def call(sock, session, op, **fields):
    request = {"op": op, **fields}
    if session:
        request["session_id"] = session
    sock.send(msgpack.packb(request, use_bin_type=True))
    return msgpack.unpackb(sock.recv(), raw=False)


def receive(sub, timeout):
    """(header fields, pixel bytes) of the next frame, None after `timeout` seconds."""
    if not sub.poll(int(timeout * 1000)):
        return None
    topic, body = sub.recv_multipart()
    magic, size, frame_id, sim_time, step = struct.unpack_from("<4sIQdQ", body)
    if magic != b"UCM1" or size != 32:
        fail(f"frame header {body[:32]!r}", PROC)
    return {"frame_id": frame_id, "sim_time": sim_time, "step": step}, body[size:]


def main():
    global PROC
    tmp = tempfile.mkdtemp(prefix="urlab_cam2026_")
    scene = camera_rig_scene(tmp)
    PROC, endpoints = start_urlab(URLAB, scene, "--ports", "auto")
    ctx = zmq.Context()
    try:
        rpc = ctx.socket(zmq.REQ)
        rpc.setsockopt(zmq.LINGER, 0)
        rpc.setsockopt(zmq.RCVTIMEO, 20000)
        rpc.connect(endpoints[3])
        hello = call(rpc, None, "hello", client_version="urlab_bridge/2026.1.0")
        sid = hello["session_id"]
        rig = next(e for e in hello["entities"] if e["prefix"] == "rig")
        cams = rig["camera_topics"]
        if not isinstance(cams, dict) or "top" not in cams:
            fail(f"camera_topics {cams!r}", PROC)
        top = cams["top"]
        for k in ("mode", "resolution", "fovy", "zmq_endpoint", "zmq_topic"):
            if k not in top:
                fail(f"camera entry without {k}: {top}", PROC)
        if top["resolution"] != [64, 48] or not top["fovy"] > 0:
            fail(f"top camera {top}", PROC)

        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, top["zmq_topic"].encode())
        sub.connect(top["zmq_endpoint"])
        bare = ctx.socket(zmq.SUB)
        bare.setsockopt(zmq.LINGER, 0)
        bare.setsockopt(zmq.SUBSCRIBE, top["bare_topic"].encode())
        bare.connect(top["zmq_endpoint"])

        ids = []
        for _ in range(5):
            got = receive(sub, 10)
            if got is None:
                fail("no frame with a header within 10 s", PROC)
            header, pixels = got
            if len(pixels) != 64 * 48 * 4:
                fail(f"{len(pixels)} pixel bytes after the header", PROC)
            ids.append(header["frame_id"])
        if ids != sorted(ids) or len(set(ids)) != len(ids):
            fail(f"frame ids {ids}", PROC)
        if not bare.poll(10000):
            fail("no bare frame", PROC)
        _, body = bare.recv_multipart()
        if len(body) != 64 * 48 * 4:
            fail(f"bare frame of {len(body)} bytes", PROC)
        print(f"headed frames {ids}")

        # Stepped: the frame of a state after the step is recognisable by its header.
        r = call(rpc, sid, "set_mode", mode="stepped")
        if r.get("current_mode") != "stepped":
            fail(f"set_mode {r}", PROC)
        r_step = r = call(rpc, sid, "step", n_steps=25)
        t = r["time"]
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            got = receive(sub, 1)
            if got and got[0]["sim_time"] == t and got[0]["step"] == r["step"]:
                break
        else:
            fail(f"no frame of the step's time {t}", PROC)

        # Streaming off and on.
        r = call(rpc, sid, "set_camera_streaming", top=False)
        if r.get("op") != "set_camera_streaming_ok" or r["streaming"]["rig/top"] is not False:
            fail(f"set_camera_streaming off: {r}", PROC)
        # Frames of steps before it may still be on their way (a loaded machine renders late):
        # no frame may show a step taken after it.
        before = r_step["step"]
        after = call(rpc, sid, "step", n_steps=5)["step"]
        end = time.monotonic() + 1.5
        while time.monotonic() < end:
            got = receive(sub, 0.1)
            if got and got[0]["step"] > before:
                fail(f"a frame of step {got[0]['step']} (stepped to {after} after "
                     f"set_camera_streaming false at step {before})", PROC)
        r = call(rpc, sid, "set_camera_streaming", top=True)
        if r["streaming"]["rig/top"] is not True:
            fail(f"set_camera_streaming on: {r}", PROC)
        if receive(sub, 10) is None:
            fail("no frame after set_camera_streaming true", PROC)
        r = call(rpc, sid, "set_camera_streaming", nose=True)
        if r.get("code") != "unknown_camera":
            fail(f"unknown camera: {r}", PROC)
        r = call(rpc, sid, "begin_pie")
        if r.get("code") != "unknown_op" or "Unreal editor" not in r.get("message", ""):
            fail(f"begin_pie: {r}", PROC)
        print("streaming off/on ok")
    finally:
        PROC.terminate()
        try:
            PROC.wait(timeout=20)
        except subprocess.TimeoutExpired:
            fail("urlab did not stop", PROC)
    print("PASS")


if __name__ == "__main__":
    main()
