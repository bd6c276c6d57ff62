"""The streaming topics: discovery, state and control over ZeroMQ PUB/SUB."""
import json
import time

import zmq

from urlab_client import wire


class Robot:
    """One articulation as discovery describes it."""

    def __init__(self, info):
        self.name = info["robot"]
        self.actuator_names = list(info["names"])      # short names, as in the robot's MJCF
        self.actuator_ids = list(info["ids"])
        self.mins = list(info["mins"])
        self.maxs = list(info["maxs"])
        self.cameras = list(info.get("camera_list", []))
        prefix = self.name + "_"
        self._ids = {}
        for short, aid in zip(self.actuator_names, self.actuator_ids):
            self._ids[short] = aid              # "shoulder_motor"
            self._ids[prefix + short] = aid     # the full name "arm_shoulder_motor" too

    @property
    def actuator_names_short(self):
        """Actuator names as written in the robot's own MJCF (what actuator_names holds)."""
        return list(self.actuator_names)

    def actuator_id(self, name_or_id):
        """The global id of an actuator given by short name, full name or id."""
        if isinstance(name_or_id, int):
            if name_or_id not in self.actuator_ids:
                raise KeyError(f"{self.name}: no actuator id {name_or_id}")
            return name_or_id
        try:
            return self._ids[name_or_id]
        except KeyError:
            raise KeyError(f"{self.name}: no actuator '{name_or_id}' "
                           f"(known: {', '.join(self.actuator_names)})") from None

    def __repr__(self):
        return f"Robot({self.name!r}, actuators={self.actuator_names})"


class StreamClient:
    """Connects to a running `urlab run` (or `urlab view`).

    host: the simulator's address; the ports default to docs/protocol.md's (5555 state, 5556 control,
    5557 info), or give full endpoints.
    """

    def __init__(self, host="127.0.0.1", state=None, control=None, info=None, context=None):
        self._ctx = context or zmq.Context.instance()
        self.state_endpoint = state or f"tcp://{host}:5555"
        self.control_endpoint = control or f"tcp://{host}:5556"
        self.info_endpoint = info or f"tcp://{host}:5557"
        self._state = self._ctx.socket(zmq.SUB)
        self._state.setsockopt(zmq.LINGER, 0)
        self._state.setsockopt(zmq.SUBSCRIBE, b"")
        self._state.connect(self.state_endpoint)
        self._info = self._ctx.socket(zmq.SUB)
        self._info.setsockopt(zmq.LINGER, 0)
        self._info.setsockopt(zmq.SUBSCRIBE, b"")
        self._info.connect(self.info_endpoint)
        self._control = self._ctx.socket(zmq.PUB)
        self._control.setsockopt(zmq.LINGER, 0)
        self._control.connect(self.control_endpoint)
        self.robots = {}
        self.state = {}

    def close(self):
        for s in (self._state, self._info, self._control):
            s.close(0)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def discover(self, timeout=5.0, expect=None):
        """Waits for discovery messages; returns {robot name: Robot}.

        Returns once every robot in `expect` (names) is known, or when no new robot arrived for
        one second after the first, or raises TimeoutError after `timeout` seconds with none.
        """
        end = time.monotonic() + timeout
        last_new = None
        while time.monotonic() < end:
            if expect and all(n in self.robots for n in expect):
                break
            if last_new and not expect and time.monotonic() - last_new > 1.0:
                break
            if self._info.poll(50):
                info = json.loads(self._info.recv())
                if info.get("type") == "actuator_list" and info["robot"] not in self.robots:
                    self.robots[info["robot"]] = Robot(info)
                    last_new = time.monotonic()
        if not self.robots or (expect and not all(n in self.robots for n in expect)):
            raise TimeoutError(f"no discovery from {self.info_endpoint} within {timeout} s")
        return self.robots

    def poll(self, timeout=0.0):
        """Reads every state message waiting (after waiting up to `timeout` s for the first).

        Returns self.state: {robot: {"joint": {name: {...}}, "base_state": {...},
        "sensor": {name: values}}}, numpy arrays, newest values.
        """
        if timeout > 0:
            self._state.poll(int(timeout * 1000))
        while True:
            try:
                topic, payload = self._state.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                return self.state
            except ValueError:
                continue  # not two frames: not ours
            parts = topic.decode().split("/", 2)
            if len(parts) != 3:
                continue
            robot, kind, name = parts
            entry = self.state.setdefault(robot, {"joint": {}, "base_state": {}, "sensor": {}})
            if kind == "joint":
                entry["joint"][name] = wire.decode_joint(payload)
            elif kind == "base_state":
                entry["base_state"][name] = wire.decode_base_state(payload)
            elif kind == "sensor":
                entry["sensor"][name] = wire.decode_sensor(payload)["values"]

    def joint_position(self, robot, joint):
        """Newest qpos of a joint (first value for hinge/slide), None before any state."""
        j = self.state.get(robot, {}).get("joint", {}).get(joint)
        return None if j is None else j["qpos"][0]

    def send_control(self, robot, targets):
        """Sends one control message: {actuator name or id: value} for one robot.

        The values are targets for the robot's controller (joint positions for PD) or raw
        controls (no controller). Applied as one whole frame while the robot's control source
        is the network.
        """
        r = self._robot(robot)
        pairs = [(r.actuator_id(k), v) for k, v in targets.items()]
        self._control.send_multipart([f"{robot}/control ".encode(), wire.encode_control(pairs)])

    def set_gains(self, robot, gains):
        """Patches PD gains: {joint or actuator name: {"kp": .., "kv": .., "torque_limit": ..}}."""
        self._robot(robot)
        self._control.send_multipart([f"{robot}/set_gains ".encode(),
                                      json.dumps(gains).encode()])

    def _robot(self, robot):
        if robot not in self.robots:
            self.discover(expect=[robot])
        return self.robots[robot]
