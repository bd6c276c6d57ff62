#!/usr/bin/python3
"""End to end: a client of the 2026 vocabulary (the URLab plugin's 2026 Python client, whose
hello says client_version "urlab_bridge/...") against `urlab run` of the Go2-style scene and the
arm scene (system-chosen ports).

The client below is written from the 2026 vocabulary's tables alone (docs/protocol.md, "The 2026
dialect"): plain REQ socket and msgpack, nothing from our own client. It shows, on each scene:
connect in stepped mode; discover (the entities array, raw tables, meta's namespaces); set_ctrl
by name (control_mode raw: the values are the controls; ue_controller: the controller's
targets); step n advancing the time by exactly n*dt; qpos, qvel, root pose and sensors read from
`arts`; reset to a keyframe by its MJCF name; gains as per-name maps with defaults;
recording start/stop/save and replay load/list/set_active/start; list_keyframes records;
get_contacts' n_contacts; set_qpos by target; set_twist (a silent success without a twist
controller); option enums by name; editor operations answered unknown_op; a new hello on the
same connection drives again at once; the same data from state/full (op state_full, arts).
Then one server serves a 2026 client and one of ours at once, and a silent 2026 driver loses the
lease after the timeout. Last, on the Go2 scene with a launcher: the free bodies of no
articulation (its projectiles) are entities after the articulation, and their state is under
`scene` in step replies and state/full.
Usage: upstream2026_e2e.py URLAB_BINARY SOURCE_DIR
"""
import math
import os
import sys
import tempfile
import time

import msgpack
import zmq

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_process import fail, start_announced  # noqa: E402
import step_socket  # noqa: E402
from step_socket import StepSocket  # noqa: E402

CLIENT_VERSION = "urlab_bridge/2026.1.0"
NAMESPACES = {"scene", "sim", "runtime", "outliner", "debug", "viewport"}
PROC = None


def check(ok, message):
    if not ok:
        fail(message, PROC)


def failed(message):
    fail(message, PROC)


class Bridge(StepSocket):
    """The 2026 client's side of the step socket: its version in hello, every request numbered."""

    def __init__(self, endpoint, ctx):
        super().__init__(endpoint, ctx, failed, number_requests=True)

    def hello(self, **fields):
        return super().hello(client_version=CLIENT_VERSION, **fields)


def refused(code, fn, *args, **kwargs):
    return step_socket.refused(code, failed, fn, *args, **kwargs)


def close(a, b, tol=1e-9):
    return len(a) == len(b) and all(abs(x - y) <= tol for x, y in zip(a, b))


def latest_state_full(sub, frame_id, timeout=10.0):
    """The state/full snapshot of frame `frame_id` (older ones skipped)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not sub.poll(200):
            continue
        topic, body = sub.recv_multipart()
        check(topic == b"state/full", f"topic {topic!r}")
        snap = msgpack.unpackb(body, raw=False)
        if snap.get("frame_id") == frame_id:
            return snap
    fail(f"no state/full snapshot of frame {frame_id}", PROC)


def exercise(ctx, a, tmp, art, keyframe, free_base):
    """The 2026 client's session on one scene. Returns the client (still the driver)."""
    c = Bridge(a["endpoints"]["rpc"], ctx)
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, b"state/full")
    sub.connect(a["endpoints"]["state"])

    # Discover: the handshake.
    hello = c.hello(raw_model=True)
    check(hello["mode"] in ("freerun", "stepped"), f"hello mode {hello['mode']}")
    entities = hello["entities"]
    check(isinstance(entities, list) and len(entities) >= 1, f"entities {entities!r}")
    e = next((x for x in entities if x.get("prefix") == art), None)
    check(e is not None, f"no entity with prefix {art}: {[x.get('prefix') for x in entities]}")
    check(e["actor_name"] == art and isinstance(e["actor_id"], int), f"identity {e}")
    check(e["default_control_mode"] == "ue_controller", f"control mode {e['default_control_mode']}")
    ctl = e["controller"]
    check({"kind", "params", "schema"} <= set(ctl), f"controller {ctl}")
    check({"kp", "kv", "torque_limit"} <= set(ctl["schema"]), f"schema {ctl['schema']}")
    check(isinstance(e["camera_topics"], dict), "camera_topics is not a map")
    check(isinstance(hello["global_cameras"], dict), "global_cameras is not a map")
    check(e["has_free_base"] is free_base, f"has_free_base {e['has_free_base']}")
    for f in ("id", "free_joint", "qpos_offset", "qvel_offset", "original_names"):
        check(f in e, f"entity without {f}")
    joints, actuators = hello["raw_joints"], hello["raw_actuators"]
    check(hello.get("raw_model") is True and joints and actuators, "no raw tables")
    for j in joints:
        check({"name", "id", "type", "qpos_adr", "qvel_adr", "range", "body_id"} <= set(j), f"{j}")
        check(isinstance(j["type"], int) and not j["name"].startswith(art + "_"), f"joint {j}")
    for u in actuators:
        check({"name", "id", "ctrlrange", "gear", "joint"} <= set(u), f"actuator {u}")
        check(not u["name"].startswith(art + "_"), f"actuator name not short: {u['name']}")
    names = [u["name"] for u in sorted(actuators, key=lambda u: u["id"])]
    check(set(e["actuator_types"]) == set(names), f"actuator_types {e['actuator_types']}")
    check(any(j["type"] == 0 for j in joints) == free_base, "free joint type (mjJNT_FREE 0)")
    # Names the client matches by prefix: by category, live (prefixed) -> original (short).
    check(all(live.startswith(art + "_") and not orig.startswith(art + "_")
              for cat in ("actuators", "joints", "sensors", "bodies")
              for live, orig in e["original_names"][cat].items()),
          f"original names {e['original_names']}")

    meta = c.call("meta")
    ops = {o["name"]: o for o in meta["ops"]}
    for o in meta["ops"]:
        check({"name", "category", "namespace", "required_fields", "reply_fields"} <= set(o), f"{o}")
    for op in ("step", "reset", "list_keyframes", "get_contacts", "configure_controller",
               "set_qpos", "recording_start", "replay_load", "set_twist"):
        check(ops[op]["namespace"] in NAMESPACES, f"{op} namespace {ops[op]['namespace']}")
    check("target" in ops["set_qpos"]["required_fields"], f"set_qpos {ops['set_qpos']}")

    # Connect in stepped mode.
    mode = c.call("set_mode", mode="stepped")
    check(mode["current_mode"] == "stepped" and mode["previous_mode"] in ("freerun", "stepped"),
          f"set_mode echo {mode}")

    opts = c.call("set_sim_options", options={})["options"]
    dt = opts["timestep"]
    check(opts["integrator"] in ("euler", "rk4", "implicit"), f"integrator {opts['integrator']}")
    check(opts["cone"] in ("pyramidal", "elliptic") and
          opts["solver"] in ("pgs", "cg", "newton"), f"enums {opts}")

    # Keyframe records; reset by the MJCF name.
    keys = c.call("list_keyframes")["keyframes"]
    rec = next((k for k in keys if k["name"] == keyframe), None)
    check(rec is not None, f"no keyframe {keyframe}: {keys}")
    for f in ("time", "qpos", "qvel", "ctrl", "mocap_pos", "mocap_quat"):
        check(f in rec, f"keyframe record without {f}")
    r = c.call("reset", keyframe_name=keyframe)
    check(r["op"] in ("reset_ok", "step_ok") and "arts" in r and "per_articulation" not in r,
          f"reset reply keys {sorted(r)}")
    q = r["arts"][art]["qpos"]
    check(close(q, rec["qpos"][:len(q)]), f"reset to {keyframe}: {q} vs {rec['qpos']}")
    check(isinstance(r["frame_id"], int), "no frame_id")

    # step n: exactly n * dt.
    t0 = c.call("step", n_steps=1)["time"]
    r = c.call("step", n_steps=10)
    check(abs(r["time"] - t0 - 10 * dt) < 1e-9, f"10 steps advanced {r['time'] - t0}, dt {dt}")
    check(r["frame_id"] > 0, "frame_id")

    # set_ctrl by name. raw: the actuators take the values; ue_controller: they are targets.
    pick = {names[0]: 0.375, names[-1]: -0.125}
    r = c.call("step", per_articulation={art: {"ctrl": pick, "control_mode": "raw"}})
    ctrl = r["arts"][art]["ctrl"]
    check(ctrl[0] == 0.375 and ctrl[-1] == -0.125, f"raw ctrl {ctrl}")
    r = c.call("step", per_articulation={art: {"ctrl": pick, "control_mode": "ue_controller"}})
    ctrl = r["arts"][art]["ctrl"]
    check(ctrl[0] != 0.375 or ctrl[-1] != -0.125, f"controller targets applied as controls {ctrl}")
    refused("bad_value", c.call, "step",
            per_articulation={art: {"ctrl": pick, "control_mode": "telepathy"}})

    # qpos, qvel, sensors, root pose from arts (level full: bodies by name).
    c.call("step", n_steps=5)
    # forward: body poses of this qpos (after mj_step they are those of the step's start).
    r = c.call("forward", observations="full")
    s = r["arts"][art]
    check(len(s["qpos"]) >= len(s["qvel"]) > 0, "qpos/qvel")
    check(s["sensors"] and all(not k.startswith(art + "_") for k in s["sensors"]), "sensors")
    check(all(isinstance(v, list) for v in s["sensors"].values()), "sensor values")
    check("bodies" in s and "xpos" not in s, f"full level keys {sorted(s)}")
    if free_base:
        o = e["qpos_offset"]
        root = s["qpos"][o:o + 7]
        check(any(close(b["xpos"], root[:3], 1e-6) and close(b["xquat"], root[3:], 1e-6)
                  for b in s["bodies"].values()), f"root pose {root} is no body's pose")
        check(len(s["qvel"][e["qvel_offset"]:e["qvel_offset"] + 6]) == 6, "root twist")

    # Gains as per-name maps, defaults for the rest, echoed in the same shape.
    g = c.call("configure_controller", articulation=art,
               params={"kp": {names[0]: 71.0}, "default_kp": 55.0, "default_kv": 3.0})["params"]
    check(g["kp"][names[0]] == 71.0, f"kp {g['kp']}")
    check(all(v == 55.0 for k, v in g["kp"].items() if k != names[0]), f"default kp {g['kp']}")
    check(set(g["kv"]) == set(names) and all(v == 3.0 for v in g["kv"].values()), f"kv {g['kv']}")
    check(g.get("default_kp") == 55.0, "defaults not echoed")

    n = c.call("get_contacts")["n_contacts"]
    check(isinstance(n, int) and (n > 0 or not free_base), f"n_contacts {n}")

    r = c.call("set_qpos", target=art, target_by="actor_name", qpos=rec["qpos"][:len(q)])
    check(r["target"] == art and r["actor_id"] == e["actor_id"] and close(r["qpos"], rec["qpos"][:len(q)])
          and "free_base_shortcut" in r and "arts" in r, f"set_qpos reply {sorted(r)}")

    tw = c.call("set_twist", articulation=art, linear=[0.2, 0.0, 0.0], angular=[0.0, 0.0, 0.1])
    check(tw["op"] == "set_twist_ok", f"set_twist {tw}")
    check(c.call("set_control_source", source="zmq")["source"] == "zmq", "control source echo")

    e = refused("unknown_op", c.call, "begin_pie")
    check("Unreal editor" in e.message, f"begin_pie message: {e.message}")
    refused("unknown_op", c.call, "upload_model_manifest", name="go2")

    # Recording and replay.
    started = c.call("recording_start", max_duration_s=30.0)
    check("name" in started and "max_duration_s" in started, f"recording_start {started}")
    c.call("step", n_steps=20)
    stopped = c.call("recording_stop")
    check(stopped["frame_count"] > 0 and stopped["sim_duration_s"] > 0, f"recording_stop {stopped}")
    saved = c.call("recording_save", name=f"{art}_saved.urrec")
    check(os.path.isabs(saved["absolute_path"]) and os.path.exists(saved["absolute_path"]),
          f"recording_save {saved}")
    loaded = c.call("replay_load", path=saved["absolute_path"])
    check(loaded["total_frames"] > 0 and isinstance(loaded["name"], str), f"replay_load {loaded}")
    listed = c.call("replay_list_sessions")["sessions"]
    check(listed == [loaded["name"]], f"replay_list_sessions {listed}")
    c.call("replay_set_active", name=loaded["name"])
    play = c.call("replay_start")
    check(play["active_session"] == loaded["name"] and play["total_frames"] == loaded["total_frames"],
          f"replay_start {play}")
    c.call("replay_stop")

    # state/full: the same data, under arts, named state_full.
    r = None
    for _ in range(50):  # the subscription joins
        r = c.call("step", n_steps=1)
        if sub.poll(100):
            break
    snap = latest_state_full(sub, r["frame_id"])
    check(snap.get("op") == "state_full" and "arts" in snap, f"snapshot keys {sorted(snap)}")
    check(snap["arts"][art]["qpos"] == r["arts"][art]["qpos"] and
          snap["arts"][art]["qvel"] == r["arts"][art]["qvel"] and
          snap["arts"][art]["sensors"] == r["arts"][art]["sensors"], "state/full differs from step")
    check(snap["time"] == r["time"], "state/full time")
    sub.close(0)

    # Reconnect: a new hello on the same connection drives again at once.
    first = c.session_id
    c.hello()
    check(c.session_id != first, "the same session id twice")
    r = c.call("step", n_steps=2)
    check(abs(r["time"] - snap["time"] - 2 * dt) < 1e-9, "stepping after the new hello")
    return c


def free_bodies(ctx, tmp):
    """The launcher scene's projectiles in the handshake and under `scene`."""
    global PROC
    PROC, a = start_announced(URLAB, os.path.join(SOURCE, "examples", "scenes",
                                                  "go2_launcher.yaml"),
                              "--no-cameras", "--files-dir", tmp)
    try:
        c = Bridge(a["endpoints"]["rpc"], ctx)
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, b"state/full")
        sub.connect(a["endpoints"]["state"])
        hello = c.hello(raw_model=True)
        entities = hello["entities"]
        check(entities[0]["prefix"] == "dog", f"first entity {entities[0]['prefix']}")
        bodies = entities[1:]
        check(len(bodies) == 8, f"{len(bodies)} free bodies, want the launcher's pool of 8")
        raw = {j["name"]: j for j in hello["raw_joints"]}
        for i, e in enumerate(bodies):
            check(e["actor_id"] == i + 1 and e["has_free_base"] is True and
                  e["qpos_offset"] == 0 and e["qvel_offset"] == 0, f"free body {e}")
            check(e["prefix"].startswith("cannon_"), f"free body name {e['prefix']}")
            j = raw.get(e["free_joint"])
            check(j is not None and j["type"] == 0 and j["body_id"] == e["id"],
                  f"free joint {e['free_joint']} in raw_joints: {j}")
        c.call("set_mode", mode="stepped")
        c.call("set_control_source", source="zmq")
        shot = c.call("fire_launcher", launcher="cannon")
        name = bodies[shot["projectile"]]["prefix"]
        r = c.call("step", n_steps=1)
        check(set(r["scene"]) == {e["prefix"] for e in bodies}, f"scene keys {sorted(r['scene'])}")
        s = r["scene"][name]
        check(len(s["qpos"]) == 7 and len(s["qvel"]) == 6, f"scene[{name}] {s}")
        check(s["qvel"][0] > 1.0, f"the launched projectile does not move: {s['qvel']}")
        for _ in range(50):  # the subscription joins
            r = c.call("step", n_steps=1)
            if sub.poll(100):
                break
        snap = latest_state_full(sub, r["frame_id"])
        check(snap["scene"][name] == r["scene"][name], "state/full scene differs from step")
        sub.close(0)
        c.close()
        print(f"go2_launcher.yaml: {len(bodies)} free bodies in entities and scene")
    finally:
        PROC.terminate()
        PROC.wait(timeout=30)


def main():
    global PROC
    tmp = tempfile.mkdtemp(prefix="urlab_upstream2026_")
    ctx = zmq.Context()
    scenes = [("go2_network.yaml", "dog", "home", True), ("arm_network.yaml", "arm", "rest", False)]
    for scene, art, keyframe, free_base in scenes:
        PROC, a = start_announced(URLAB, os.path.join(SOURCE, "examples", "scenes", scene),
                                  "--no-cameras", "--files-dir", tmp)
        try:
            c = exercise(ctx, a, tmp, art, keyframe, free_base)
            if not free_base:
                tw = c.call("set_twist", articulation=art, linear=[0.1, 0, 0], angular=[0, 0, 0])
                check(tw["op"] == "set_twist_ok", "set_twist without a twist controller")

            # Ours at once: our vocabulary on the same server, not the driver.
            ours = Bridge(a["endpoints"]["rpc"], ctx)
            info = ours.call("hello")
            ours.session_id = info["session_id"]
            check(isinstance(info["entities"], dict) and info["articulations"][0]["name"] == art,
                  "our hello changed")
            check(info["mode"] == "direct", f"our mode name {info['mode']}")
            fwd = ours.call("forward")
            check("per_articulation" in fwd and "arts" not in fwd, f"our forward {sorted(fwd)}")
            refused("not_driver", ours.call, "step")
            r = c.call("step", n_steps=1)
            check("arts" in r, "2026 step after ours")
            # A silent driver loses the lease after the timeout (5 s).
            time.sleep(5.6)
            mine = ours.call("step", n_steps=1)
            check(mine["per_articulation"][art]["qpos"] is not None, "ours drives after")
            refused("not_driver", c.call, "step")
            print(f"{scene}: 2026 client ok; {len(ops_count(c))} ops in meta")
            c.close()
            ours.close()
        finally:
            PROC.terminate()
            PROC.wait(timeout=30)
    free_bodies(ctx, tmp)
    print("PASS")


def ops_count(c):
    return c.call("meta")["ops"]


if __name__ == "__main__":
    main()
