#!/usr/bin/python3
"""Writes the fuzzers' seed corpora under fuzz/corpus/<target>/ (committed; small).

  fuzz_mjcf_reader    the MJCF test corpus and broken models (tests/data/mjcf)
  fuzz_scene          scene YAML, alone (the harness's arm.xml) or with an MJCF part
  fuzz_net_control    control payloads (first byte 0) and set_gains JSON (first byte 1)
                      for the harness's arm (actuator ids 0..2)
  fuzz_step_request   step-server requests in msgpack and JSON, every operation of
                      docs/protocol.md; "@"*20 stands for the session id the harness obtains
  fuzz_shm_channel    header writes of the shared-memory channel (forged capacities, lengths,
                      sequences, flags) followed by step-server requests

Usage: /usr/bin/python3 tools/gen_fuzz_corpus.py   (from anywhere; rewrites the folders)
Needs python3-msgpack (Debian), as the Python client does.
"""
import glob
import hashlib
import json
import os
import shutil
import struct

import msgpack

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fuzz", "corpus")
SID = "@" * 20  # the harness replaces it with the session id from its own hello


def target_dir(name):
    d = os.path.join(OUT, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


def put(d, data, stem=None):
    if isinstance(data, str):
        data = data.encode()
    name = stem or hashlib.sha1(data).hexdigest()[:16]
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def mjcf_reader():
    d = target_dir("fuzz_mjcf_reader")
    data = os.path.join(ROOT, "tests", "data", "mjcf")
    files = sorted(glob.glob(os.path.join(data, "corpus", "*.xml")))
    files += sorted(glob.glob(os.path.join(data, "broken", "*.xml")))[:20]
    files += sorted(glob.glob(os.path.join(data, "dialect3x", "*.xml")))
    for path in files:
        with open(path, "rb") as f:
            text = f.read()
        if len(text) <= 16384:
            put(d, text, os.path.basename(os.path.dirname(path)) + "_" + os.path.basename(path))


SCENES = [
    "articulations:\n  - {name: arm, mjcf: arm.xml}\n",
    "control_source: network\narticulations:\n"
    "  - {name: arm, mjcf: arm.xml, keyframe: raised, hold_keyframe: true,\n"
    "     controller: {type: pd, kp: 400, kv: 20, gains: {elbow: {kp: 200, kv: 10}}}}\n",
    "articulations:\n  - name: left\n    mjcf: arm.xml\n    pos: [0, -0.6, 0]\n"
    "    controller: {type: passthrough}\n    control_source: ui\n"
    "  - name: right\n    mjcf: arm.xml\n    pos: [0, 0.6, 0]\n    euler: [0, 0, 90]\n"
    "    keyframe: home\n",
    "options: {timestep: 0.001, gravity: [0, 0, -1], flag.contact: disable}\n"
    "size: {nconmax: 100, njmax: 300}\narticulations:\n  - {name: a, mjcf: arm.xml}\n",
    "articulations:\n  - name: arm\n    mjcf: arm.xml\n    controller:\n      type: keyframe\n"
    "      loop: true\n      start_delay: 0.1\n      sequence:\n"
    "        - {keyframe: home, hold: 0.2, blend: 0.1}\n"
    "        - {keyframe: raised, hold: 0.3}\n",
    "articulations:\n  - {name: r, mjcf: robot.xml}\n",
    "articulations:\n  - {name: r, mjcf: robot.xml, include_world: false, quat: [0, 0, 0, 1]}\n"
    "  - {name: s, mjcf: robot.xml, axisangle: [0, 0, 1, 90], options: {timestep: 0.004}}\n",
    "network: {enabled: false, step_mode: direct}\narticulations:\n"
    "  - {name: arm, mjcf: arm.xml, controller: {type: pd, torque_limit: 5}}\n",
    "articulations:\n  - {name: a, mjcf: arm.xml}\n  - {name: a_b, mjcf: arm.xml}\n",
    "articulations:\n  - {name: arm, mjcf: arm.xml, keyframe: missing}\n",
]


def scene():
    d = target_dir("fuzz_scene")
    for s in SCENES:
        put(d, s)
    # Scenes over a robot of the MJCF corpus (robot.xml is the part after the separator).
    data = os.path.join(ROOT, "tests", "data", "mjcf", "corpus")
    robot = "articulations:\n  - {name: r, mjcf: robot.xml}\n"
    two = ("articulations:\n  - {name: r, mjcf: robot.xml}\n"
           "  - {name: q, mjcf: robot.xml, pos: [2, 0, 0]}\n")
    for i, name in enumerate(["bodies_geoms.xml", "actuators_all.xml", "keyframes.xml",
                              "defaults_nested.xml", "tendons.xml", "sensors_all.xml",
                              "equality.xml", "options_flags.xml", "orientation_degree.xml",
                              "contact.xml"]):
        with open(os.path.join(data, name)) as f:
            xml = f.read()
        put(d, (two if i % 2 else robot) + "\n---mjcf---\n" + xml)
    for name in ["go2_like.xml", "arm_servos.xml", "frames.xml"]:
        with open(os.path.join(ROOT, "tests", "data", "mjcf", "dialect3x", name)) as f:
            put(d, robot + "\n---mjcf---\n" + f.read())


def control_payload(pairs):
    return struct.pack("<i", len(pairs)) + b"".join(struct.pack("<if", i, v) for i, v in pairs)


def net_control():
    d = target_dir("fuzz_net_control")
    for pairs in [[], [(0, 0.5)], [(0, 0.5), (1, -0.3), (2, 0.05)], [(2, 1.0), (2, 2.0)],
                  [(1, 1e30)], [(7, 1.0)], [(0, -0.0), (1, 3.5)]]:
        put(d, b"\x00" + control_payload(pairs))
    put(d, b"\x00" + struct.pack("<i", 2) + struct.pack("<if", 0, 1.0))  # truncated
    put(d, b"\x00" + struct.pack("<i", -1))
    for gains in [{"elbow": {"kp": 10, "kv": 1}},
                  {"shoulder_motor": {"kp": 200, "kv": 20, "torque_limit": 5}},
                  {"arm_slider_servo": {"kv": 0.5}, "slider": {"kp": 0}},
                  {"elbow_motor": {}},
                  {"nope": {"kp": 1}},
                  {"elbow": {"kp": -1}},
                  {"elbow": {"damping": 1}}]:
        put(d, b"\x01" + json.dumps(gains).encode())
    put(d, b"\x01[1, 2, 3]")
    put(d, b"\x01" + b"{\"elbow\": " * 3 + b"1" + b"}" * 3)  # deeper than set_gains' 2
    put(d, b"\x01{\"elbow\": {\"kp\": 1e999}}")


REQUESTS = [
    {"op": "hello"},
    {"op": "hello", "observations": "full", "arrays": "binary", "seq": 1},
    {"op": "meta"},
    {"op": "bye", "session_id": SID},
    {"op": "step", "session_id": SID},
    {"op": "step", "session_id": SID, "n_steps": 5, "observations": "full", "seq": 3},
    {"op": "step", "session_id": SID, "per_articulation": {"arm": {"ctrl": [0.1, -0.2, 0.05]}}},
    {"op": "step", "session_id": SID,
     "per_articulation": {"arm": {"ctrl_map": {"elbow_motor": 1.5, "shoulder": -1}}}},
    {"op": "reset", "session_id": SID},
    {"op": "reset", "session_id": SID, "keyframe_name": "arm_raised"},
    {"op": "reset", "session_id": SID, "per_articulation_qpos": {"arm": {"elbow": 0.3}}},
    {"op": "forward", "session_id": SID},
    {"op": "set_mode", "session_id": SID, "mode": "direct"},
    {"op": "set_mode", "session_id": SID, "mode": "puppet"},
    {"op": "set_paused", "session_id": SID, "paused": True},
    {"op": "set_sim_speed", "session_id": SID, "percent": 50},
    {"op": "set_control_source", "session_id": SID, "source": "ui", "articulation": "arm"},
    {"op": "set_qpos", "session_id": SID, "articulation": "arm", "qpos": [0.1, 0.2, 0.03]},
    {"op": "set_mocap_pose", "session_id": SID, "body": "arm_target", "pos": [0, 0, 1.5],
     "quat": [1, 0, 0, 0]},
    {"op": "read_mocap_pose", "session_id": SID, "body": "arm_target"},
    {"op": "list_keyframes", "session_id": SID},
    {"op": "set_sim_options", "session_id": SID,
     "options": {"timestep": 0.001, "gravity": [0, 0, -1], "iterations": 50,
                 "integrator": "RK4", "cone": "elliptic", "solver": "CG"}},
    {"op": "get_counters", "session_id": SID},
    {"op": "hello", "include_assets": True, "encoding": "json"},
    {"op": "step", "session_id": SID, "qpos": [0.1, 0.2, 0.3], "qvel": [0, 0, 0],
     "ctrl": [0, 0, 0], "time": 1.5},
    {"op": "step", "session_id": SID,
     "per_articulation": {"arm": {"qpos": [0.1, 0.2, 0.3], "qvel": [0, 0, 0]}}},
    {"op": "get_contacts", "session_id": SID},
    {"op": "get_contacts", "session_id": SID, "max_contacts": 2,
     "filter": {"body1": "arm_upper", "geom2": "arm_floor"}},
    {"op": "set_twist", "session_id": SID, "articulation": "arm", "linear": [1, 0, 0],
     "angular": [0, 0, 0.5]},
    {"op": "configure_controller", "session_id": SID, "articulation": "arm",
     "params": {"kp": 10, "gains": {"elbow": {"kv": 2}}}},
    {"op": "snapshot_save", "session_id": SID, "path": "state.urrec"},
    {"op": "snapshot_save", "session_id": SID, "path": "state.urrec", "overwrite": True},
    {"op": "snapshot_save", "session_id": SID, "path": "../arm.xml"},
    {"op": "snapshot_load", "session_id": SID, "path": "state.urrec"},
    {"op": "recording_start", "session_id": SID, "path": "run.urrec"},
    {"op": "recording_save", "session_id": SID, "path": "copy.urrec", "overwrite": True},
    {"op": "replay_load", "session_id": SID, "path": "run.urrec.part"},
    {"op": "replay_unload", "session_id": SID},
    {"op": "cancel", "session_id": SID},
    {"op": "set_sim_options", "session_id": SID,
     "options": {"impratio": -1, "tolerance": 1e-9, "density": 1.2, "viscosity": 0}},
    {"op": "set_qpos", "session_id": SID, "articulation": "arm", "qpos": [1e300, 0, 0]},
    {"op": "step", "session_id": "nobody"},
    {"op": "no_such_op", "session_id": SID},
    {"session_id": SID},
]


def step_request():
    d = target_dir("fuzz_step_request")
    for r in REQUESTS:
        put(d, msgpack.packb(r, use_bin_type=True))
        put(d, json.dumps(r))
    put(d, msgpack.packb([1, 2, 3]))
    # Nesting at and beyond the depth limit (32, src/net/request_limits.h) in both encodings.
    for depth in (31, 40):
        put(d, '{"op": "meta", "seq": ' + "[" * depth + "1" + "]" * depth + "}")
        put(d, b"\x82\xa2op\xa4meta\xa3seq" + b"\x91" * depth + b"\x01")
    put(d, b"{not json")
    put(d, b"")


def shm_write(offset, value, wide=True):
    return struct.pack("<HBQ", offset, 1 if wide else 0, value)


def shm_channel():
    d = target_dir("fuzz_shm_channel")
    # No header write: requests as over ZeroMQ.
    for r in REQUESTS[:20]:
        put(d, b"\x00" + msgpack.packb(r, use_bin_type=True))
    hello = msgpack.packb({"op": "meta"}, use_bin_type=True)
    size = 4096 + (1 << 20) + (64 << 20)  # the file the server makes by default
    # Forged capacities (issue 38, case 1: the server wrote its reply at 4096 + this), lengths
    # beyond the slot, sequences, closed flags.
    for writes in ([shm_write(16, 1 << 40)], [shm_write(16, size - 4160)],
                   [shm_write(16, 2**64 - 1), shm_write(24, 2**64 - 1)],
                   [shm_write(200, 1 << 20 + 1)], [shm_write(200, 2**64 - 1)],
                   [shm_write(192, 0, wide=False)], [shm_write(56, 1, wide=False)],
                   [shm_write(12, 0, wide=False), shm_write(8, 7, wide=False)],
                   [shm_write(264, 2**63), shm_write(256, 5, wide=False)]):
        put(d, bytes([len(writes)]) + b"".join(writes) + hello)


if __name__ == "__main__":
    mjcf_reader()
    scene()
    net_control()
    step_request()
    shm_channel()
    for t in sorted(os.listdir(OUT)):
        n = len(os.listdir(os.path.join(OUT, t)))
        print(f"{t}: {n} seeds")
