#!/usr/bin/python3
"""End to end: the URLab plugin's 2026 client as it learns names, against `urlab run` of the
two-robot scene of examples/scenes/unitree_style.yaml (a Go2-style dog under a gait controller
and an arm under a passthrough; the arm's ids and addresses come after the dog's), system-chosen
ports and a files folder of its own.

Written from docs/protocol.md, "The 2026 dialect" alone, doing what that client does: a 2026
hello (client_version "urlab_bridge/...", asking for nothing), then its name maps built only from
the raw tables inside each element of hello_ok's `entities` (raw_model, raw_joints,
raw_actuators; sensors from the step reply), `original_names` inverted category by category,
and `controller.schema` read entry by entry with .get (values checked against min/max before
sending). Through those maps: step with controls by name (a ctrl vector of each articulation's
length), gains by name, recording_save to an absolute path inside the files folder (the path a
user types) and replay_load of it. The paths that stay refused: outside the folder, escaping it
by "..", a link out, and an absolute path from a client of ours. Last, the model the handshake
carries as `mjb` loads in the `mujoco` Python package of this environment (MuJoCo 3.x, the
server's major.minor), and its names and ids agree with the raw tables.
Usage: client2026_maps_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import sys
import tempfile

import zmq

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_process import fail, start_announced  # noqa: E402
import step_socket  # noqa: E402
from step_socket import StepSocket  # noqa: E402

CLIENT_VERSION = "urlab_bridge/2026.1.0"
# The two robots of examples/scenes/unitree_style.yaml without hold_keyframe (which holds the
# keyframe's targets against a step's raw controls), the network their control source.
SCENE = """control_source: network
articulations:
  - name: dog
    mjcf: {robots}/go2/scene.xml
    controller: {{type: gait, kp: 40, kv: 1, torque_limit: 45}}
    keyframe: home
  - name: arm
    mjcf: {robots}/arm/arm.xml
    pos: [0.8, 0, 0]
    controller: {{type: passthrough}}
    keyframe: home
"""
PROC = None


def check(ok, message):
    if not ok:
        fail(message, PROC)


def failed(message):
    fail(message, PROC)


def Connection(endpoint, ctx):  # noqa: N802 - a StepSocket as this test's clients use it
    return StepSocket(endpoint, ctx, failed)


def refused(code, fn, *args, **kwargs):
    return step_socket.refused(code, failed, fn, *args, **kwargs)


class Robot:
    """The client's name maps of one element of `entities`, from its raw tables only."""

    def __init__(self, entity):
        check(entity.get("raw_model") is True,
              f"entity {entity.get('prefix')} carries no raw tables: {sorted(entity)}")
        self.prefix = entity["prefix"]
        self.joints = {j["name"]: j for j in entity["raw_joints"]}
        self.actuators = list(entity["raw_actuators"])
        # name -> its place in the ctrl vector (the tables' order)
        self.ctrl_index = {u["name"]: i for i, u in enumerate(self.actuators)}
        check(len(self.ctrl_index) == len(self.actuators), f"{self.prefix}: duplicate names")
        # original_names, category by category: original (as the user writes it) -> live.
        names = entity["original_names"]
        check(isinstance(names, dict) and
              {"actuators", "joints", "sensors", "bodies"} <= set(names),
              f"{self.prefix}: original_names not by category: {names}")
        self.live = {cat: {orig: live for live, orig in names[cat].items()}
                     for cat in ("actuators", "joints", "sensors", "bodies")}
        self.schema = entity["controller"]["schema"]

    def ctrl(self, by_name):
        """The ctrl vector of `by_name` {actuator: value}; zero elsewhere, each value clamped
        to its actuator's ctrlrange (a limited one)."""
        vector = [0.0] * len(self.actuators)
        for name, value in by_name.items():
            check(name in self.ctrl_index, f"{self.prefix}: no actuator {name}")
            lo, hi = self.actuators[self.ctrl_index[name]]["ctrlrange"]
            vector[self.ctrl_index[name]] = min(max(value, lo), hi) if lo < hi else value
        return vector

    def gains(self, params):
        """configure_controller's params checked against the schema as the client does."""
        for key, value in params.items():
            entry = self.schema.get(key)
            check(entry is not None, f"{self.prefix}: the schema has no {key}: {self.schema}")
            kind, lo, hi = entry.get("type"), entry.get("min"), entry.get("max")
            values = value.values() if kind == "per_joint" else [value]
            check(kind in ("per_joint", "scalar"), f"{key}: type {kind}")
            check(kind != "per_joint" or isinstance(value, dict), f"{key} is a map by name")
            for v in values:
                check((lo is None or v >= lo) and (hi is None or v <= hi),
                      f"{key} {v} outside [{lo}, {hi}]")
            if kind == "per_joint":
                for name in value:
                    check(name in self.ctrl_index or name in self.joints,
                          f"{key}: {name} is not in the maps")
        return params


def main():
    global PROC
    files = tempfile.mkdtemp(prefix="urlab_client2026_")
    outside = tempfile.mkdtemp(prefix="urlab_client2026_out_")
    ctx = zmq.Context()
    scene = os.path.join(tempfile.mkdtemp(prefix="urlab_client2026_scene_"), "scene.yaml")
    with open(scene, "w") as f:
        f.write(SCENE.format(robots=os.path.join(SOURCE, "tests", "data", "mjcf", "robots")))
    PROC, a = start_announced(URLAB, scene, "--no-cameras", "--files-dir", files)
    try:
        c = Connection(a["endpoints"]["rpc"], ctx)
        hello = c.hello(client_version=CLIENT_VERSION)
        check(hello["op"] == "hello_ok", f"hello {hello}")
        entities = hello["entities"]
        check(isinstance(entities, list), f"entities is not an array: {type(entities)}")
        robots = {r.prefix: r for r in (Robot(e) for e in entities)}
        check({"dog", "arm"} <= set(robots), f"entities {sorted(robots)}")
        dog, arm = robots["dog"], robots["arm"]
        check(len(dog.actuators) == 12 and len(arm.actuators) > 0,
              f"{len(dog.actuators)} dog actuators, {len(arm.actuators)} arm actuators")
        check(all(not n.startswith("dog_") for n in dog.ctrl_index), "names not short")
        # A new hello (refresh) carries them again, unasked.
        again = c.hello(client_version=CLIENT_VERSION)
        check([e.get("raw_actuators") for e in again["entities"]] ==
              [e.get("raw_actuators") for e in entities], "a second hello_ok's raw tables")

        c.call("set_mode", mode="stepped")  # an error here is fatal to the client
        c.call("set_control_source", source="zmq")

        # step, controls by name -> a ctrl vector per articulation, of its length.
        dog_ctrl = dog.ctrl({name: 0.05 * (i + 1) for i, name in enumerate(dog.ctrl_index)})
        first_arm = arm.actuators[0]["name"]
        arm_ctrl = arm.ctrl({first_arm: 0.25})
        r = c.call("step", n_steps=1,
                   arts={"dog": {"ctrl": dog_ctrl, "control_mode": "raw"},
                         "arm": {"ctrl": arm_ctrl, "control_mode": "raw"}})
        check(r["op"] == "step_ok", f"step {r}")
        check(r["arts"]["dog"]["ctrl"] == dog_ctrl, f"dog ctrl {r['arts']['dog']['ctrl']}")
        check(r["arts"]["arm"]["ctrl"] == arm_ctrl, f"arm ctrl {r['arts']['arm']['ctrl']}")
        # Joints by name: each qpos slice where the table puts it.
        for robot in (dog, arm):
            q = r["arts"][robot.prefix]["qpos"]
            for j in robot.joints.values():
                check(0 <= j["qpos_index"] < len(q), f"{robot.prefix} {j['name']} qpos_index")
        # Sensors: from the step reply only, by short name; the raw table names the same ones.
        sensors = r["arts"]["dog"]["sensors"]
        raw_sensors = {s["name"] for s in next(e for e in entities if e["prefix"] == "dog")
                       .get("raw_sensors", [])}
        check(set(sensors) == raw_sensors, f"sensors {sorted(sensors)} vs {sorted(raw_sensors)}")

        # Gains by name through the schema; the reply's params in the same shape.
        names = list(dog.ctrl_index)
        params = dog.gains({"kp": {names[0]: 33.0, names[1]: 34.0}, "default_kv": 1.5})
        g = c.call("configure_controller", articulation="dog", params=params)["params"]
        check(g["kp"][names[0]] == 33.0 and g["kp"][names[1]] == 34.0, f"kp {g['kp']}")
        check(set(g["kv"]) == set(names) and all(v == 1.5 for v in g["kv"].values()),
              f"kv {g['kv']}")
        # original_names: the name the user wrote -> the live name the server takes too.
        live = dog.live["actuators"][names[2]]
        check(live == "dog_" + names[2], f"live name of {names[2]}: {live}")
        g = c.call("configure_controller", articulation="dog",
                   params=dog.gains({"kp": {names[2]: 35.0}}))["params"]
        check(g["kp"][names[2]] == 35.0, f"kp by the original name {g['kp']}")

        # Recording, saved where the user says: an absolute path inside the files folder.
        c.call("recording_start", max_duration_s=30.0)
        for _ in range(20):
            c.call("step", n_steps=1, arts={"dog": {"ctrl": dog_ctrl, "control_mode": "raw"}})
        stopped = c.call("recording_stop")
        check(stopped["frame_count"] > 0, f"recording_stop {stopped}")
        target = os.path.join(files, "maps_run.urrec")
        saved = c.call("recording_save", path=target)
        check(saved["absolute_path"] == target and os.path.isfile(target),
              f"recording_save {saved}")
        loaded = c.call("replay_load", path=target)
        check(loaded["total_frames"] > 0 and isinstance(loaded["name"], str),
              f"replay_load {loaded}")
        check(c.call("replay_list_sessions")["sessions"] == [loaded["name"]], "replay sessions")
        c.call("replay_unload", name=loaded["name"])

        # Everything else keeps today's refusals.
        refused("bad_file_name", c.call, "recording_save",
                path=os.path.join(outside, "x.urrec"))
        refused("bad_file_name", c.call, "recording_save",
                path=os.path.join(files, "..", os.path.basename(outside), "x.urrec"))
        os.symlink(outside, os.path.join(files, "out"))
        refused("bad_file_name", c.call, "recording_save",
                path=os.path.join(files, "out", "x.urrec"))
        os.symlink(os.path.join(outside, "y.urrec"), os.path.join(files, "link.urrec"))
        refused("path_not_writable", c.call, "recording_save",
                path=os.path.join(files, "link.urrec"))
        refused("file_exists", c.call, "recording_save", path=target)
        refused("bad_file_name", c.call, "replay_load", path=os.path.join(outside, "x.urrec"))
        check(os.listdir(outside) == [], f"written outside: {os.listdir(outside)}")
        ours = Connection(a["endpoints"]["rpc"], ctx)
        ours.hello()  # not the driver: recording_save needs no lease
        refused("bad_file_name", ours.call, "recording_save", path=os.path.join(files, "o.urrec"))
        ours.close()

        # The MJB path: the model the handshake carries loads in this environment's mujoco.
        import mujoco
        server = hello["mujoco_version"].split(".")[:2]
        check(server[0] == "3" and server == mujoco.__version__.split(".")[:2],
              f"server MuJoCo {hello['mujoco_version']}, client {mujoco.__version__}")
        mjb = os.path.join(outside, "model.mjb")
        with open(mjb, "wb") as f:
            f.write(hello["mjb"])
        m = mujoco.MjModel.from_binary_path(mjb)
        os.unlink(mjb)
        for robot in (dog, arm):
            for u in robot.actuators:
                check(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, u["id"]) ==
                      robot.live["actuators"].get(u["name"]),
                      f"{robot.prefix} actuator {u} vs the MJB")
            for j in robot.joints.values():
                check(m.jnt_qposadr[j["id"]] == j["qpos_adr"] and m.jnt_type[j["id"]] == j["type"],
                      f"{robot.prefix} joint {j} vs the MJB")
        check(m.nu == sum(len(r.actuators) for r in robots.values()), f"nu {m.nu}")
        print(f"PASS: {len(dog.actuators)} + {len(arm.actuators)} actuators mapped; "
              f"recording {target} saved and loaded; MJB of MuJoCo {hello['mujoco_version']} "
              f"loads in mujoco {mujoco.__version__}")
        c.close()
    finally:
        PROC.terminate()
        PROC.wait(timeout=30)


if __name__ == "__main__":
    main()
