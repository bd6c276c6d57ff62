"""Byte layouts of the streaming topics (docs/protocol.md): little-endian, packed, no padding."""
import struct

import numpy as np

JOINT_BYTES = 16
BALL_JOINT_BYTES = 44
BASE_STATE_BYTES = 52


def decode_joint(payload):
    """{"id", "qpos", "qvel", "qacc"} of a hinge/slide (1 value each) or ball joint (4/3/3)."""
    if len(payload) == JOINT_BYTES:
        jid, q, v, a = struct.unpack("<ifff", payload)
        return {"id": jid, "qpos": np.array([q]), "qvel": np.array([v]), "qacc": np.array([a])}
    if len(payload) == BALL_JOINT_BYTES:
        values = struct.unpack("<i10f", payload)
        return {"id": values[0], "qpos": np.array(values[1:5]), "qvel": np.array(values[5:8]),
                "qacc": np.array(values[8:11])}
    raise ValueError(f"joint payload of {len(payload)} bytes (expected 16 or 44)")


def decode_base_state(payload):
    """{"pos", "quat" (w x y z), "linvel", "angvel"} of a free joint."""
    if len(payload) != BASE_STATE_BYTES:
        raise ValueError(f"base_state payload of {len(payload)} bytes (expected 52)")
    v = struct.unpack("<13f", payload)
    return {"pos": np.array(v[0:3]), "quat": np.array([v[6], v[3], v[4], v[5]]),
            "linvel": np.array(v[7:10]), "angvel": np.array(v[10:13])}


def decode_sensor(payload):
    """{"id", "values"} of a sensor."""
    if len(payload) < 8:
        raise ValueError("sensor payload shorter than its header")
    sid, dim = struct.unpack_from("<ii", payload)
    if dim < 0 or len(payload) != 8 + 4 * dim:
        raise ValueError(f"sensor payload of {len(payload)} bytes for dim {dim}")
    return {"id": sid, "values": np.frombuffer(payload, dtype="<f4", offset=8).astype(float)}


def encode_control(pairs):
    """A control payload from (actuator_id, value) pairs."""
    pairs = list(pairs)
    out = struct.pack("<i", len(pairs))
    for aid, value in pairs:
        out += struct.pack("<if", int(aid), float(value))
    return out
