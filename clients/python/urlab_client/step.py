"""The step server (docs/protocol.md): request/reply over ZeroMQ REQ, msgpack; on the same host over
a shared-memory channel the server offers in hello (urlab_client.shm), with ZeroMQ as the
fallback.

    from urlab_client import StepClient
    with StepClient("tcp://127.0.0.1:5559") as sim:
        sim.set_mode("direct")                      # lockstep: physics waits for step requests
        obs = sim.step(n_steps=10, controls={"arm": {"shoulder_motor": 0.3}})
        print(obs["per_articulation"]["arm"]["qpos"])
"""
import itertools
import warnings

import msgpack
import numpy as np
import zmq

from urlab_client import shm as _shm
from urlab_client.camera import decode_frame


class UrlabError(RuntimeError):
    """An error reply: `code` is docs/protocol.md's error code."""

    def __init__(self, code, message):
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message


_F8 = np.dtype("<f8")


def _arrays(value):
    """Lists of numbers become numpy arrays, recursively. Packed f64 bytes become read-only
    views on the decoded bytes (no copy; .copy() one to modify it). Runs once per reply, so
    exact type tests (cheaper than isinstance) and a prepared dtype."""
    t = type(value)
    if t is dict:
        return {k: _arrays(v) for k, v in value.items()}
    if t is bytes or t is bytearray:
        return np.frombuffer(value, dtype=_F8)
    if t is list and value and all(isinstance(x, (int, float)) for x in value):
        return np.asarray(value, dtype=float)
    return value


def decode_observation(reply):
    """A step/reset/forward reply with numpy arrays, and camera frames as numpy images."""
    cameras = reply.pop("cameras", None)
    reply = _arrays(reply)
    if cameras is not None:
        for streams in cameras.values():
            for frame in streams.values():
                if "data" in frame:
                    frame["image"] = decode_frame(frame.pop("data"), frame["mode"],
                                                  frame["width"], frame["height"])
        reply["cameras"] = cameras
    return reply


class StepClient:
    """One session with the step server. Observers read; the first client that steps (or sends
    force=True) holds the driver lease until bye() or silence past the lease timeout.

    shared_memory=True (the default): hello asks for a shared-memory channel, which a server on
    the same host offers; every request after hello then goes over it (self.transport says
    "shm" or "zmq"). A channel that cannot be attached leaves the client on ZeroMQ (a warning);
    a server that dies or closes the channel raises urlab_client.shm.ShmError (a
    ConnectionError) within the timeout."""

    def __init__(self, endpoint="tcp://127.0.0.1:5559", observations="standard", timeout=10.0,
                 context=None, binary_arrays=True, shared_memory=True, require=None):
        """require: {"scene", "instance", "server_session"} the server must have (an announce
        file's values): another simulator on the port answers UrlabError "wrong_server"."""
        self._timeout = timeout
        self._channel = None
        self._posted = None  # the shared-memory request awaiting receive_reply
        self._ctx = context or zmq.Context.instance()
        self._socket = self._ctx.socket(zmq.REQ)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
        self._socket.connect(endpoint)
        self._seq = itertools.count(1)
        self.session_id = None
        ask = {"shm": True} if shared_memory and _shm.available() else {}
        if require:
            ask["require"] = dict(require)
        self.info = self.hello(observations=observations,
                               arrays="binary" if binary_arrays else "list", **ask)
        offer = self.info.get("shm")
        if offer:
            try:
                self._channel = _shm.ShmChannel(offer["path"], offer["generation"])
            except (OSError, _shm.ShmError) as e:
                warnings.warn(f"urlab: staying on ZeroMQ, the shared-memory channel failed: {e}")

    @property
    def transport(self):
        return "shm" if self._channel is not None else "zmq"

    def close(self):
        if self.session_id:
            try:
                self.call("bye")
            except (UrlabError, zmq.ZMQError, ConnectionError, TimeoutError):
                pass
            self.session_id = None
        if self._channel is not None:
            self._channel.close()
            self._channel = None
        self._socket.close(0)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def call(self, op, **fields):
        """Sends one request and returns the decoded reply (raises UrlabError on an error)."""
        self.send_request(op, **fields)
        return self.receive_reply(op)

    def _request(self, op, fields):
        request = {"op": op, "seq": next(self._seq), **fields}
        if self.session_id and op not in ("hello", "meta"):
            request["session_id"] = self.session_id
        return request

    def _send(self, op, head, body=None):
        """Sends one request's bytes (`head`, then `body` when given): over shared memory when
        there is a channel (hello and its assets always over ZeroMQ), else over ZeroMQ."""
        if self._channel is not None and op != "hello":
            self._posted = self._channel.post(head) if body is None else \
                self._channel.post_parts(head, body)
            return
        self._posted = None
        self._socket.send(head if body is None else head + body)

    def send_request(self, op, **fields):
        """The first half of call(): sends the request without waiting (one at a time; a vector
        env sends to every server, then gathers with receive_reply)."""
        self._send(op, msgpack.packb(self._request(op, fields), use_bin_type=True))

    def send_request_bytes(self, op, name, data, **fields):
        """send_request(op, **fields, name=data) for a large binary field (data: a C-contiguous
        buffer, e.g. a float64 numpy array): its bytes go straight into the shared-memory
        request, not through msgpack (the same message; the field's length as a bin 32)."""
        request = self._request(op, fields)
        request[name] = b""
        head = msgpack.packb(request, use_bin_type=True)
        body = memoryview(data).cast("B")
        # The map's last entry is `name: b""`, packed as bin 8 of length 0 (c4 00): the same
        # entry with the data's length as a bin 32 (c6 + 4 bytes, big-endian), the data after it.
        self._send(op, head[:-2] + b"\xc6" + body.nbytes.to_bytes(4, "big"), body)

    def set_partner_threads(self, threads):
        """The server threads one request keeps busy (a batched server's --threads): on shared
        memory, the wait for a reply spins only while a core is free beside them all."""
        if self._channel is not None:
            self._channel.partner_threads = max(1, int(threads))

    def receive_reply(self, op):
        """The second half of call(): waits for the reply to the request sent."""
        if self._posted is not None:
            view = self._channel.wait(self._posted, self._timeout)
            self._posted = None
            try:
                reply = msgpack.unpackb(view, raw=False)
            finally:
                view.release()
        else:
            try:
                reply = msgpack.unpackb(self._socket.recv(), raw=False)
            except zmq.Again:
                raise TimeoutError(f"no reply to '{op}' from the step server") from None
        if reply.get("op") == "error":
            raise UrlabError(reply.get("code"), reply.get("message", ""))
        return reply

    def hello(self, **fields):
        reply = self.call("hello", **fields)
        self.session_id = reply["session_id"]
        return reply

    def step(self, n_steps=1, controls=None, observations=None, force=False,
             include_cameras=None):
        """Runs n_steps (direct mode) with controls {articulation: [all values] or {name: v}}.

        include_cameras: True (every stream's newest frame), or {stream: "sync" | "latest"}
        ("sync" waits for a frame rendered from this step's state). The reply's
        cameras[art][stream]["image"] is a numpy array (see urlab_client.camera)."""
        fields = {"n_steps": n_steps}
        if include_cameras is not None:
            fields["include_cameras"] = include_cameras
        if controls:
            per = {}
            for art, c in controls.items():
                per[art] = {"ctrl_map": dict(c)} if isinstance(c, dict) else \
                           {"ctrl": [float(x) for x in c]}
            fields["per_articulation"] = per
        if observations:
            fields["observations"] = observations
        if force:
            fields["force"] = True
        return decode_observation(self.call("step", **fields))

    def reset(self, keyframe=None, qpos=None):
        """Resets to a keyframe (short name, e.g. "home", when only one articulation has it, or the
        full name "dog_home") or the scene's initial state; qpos {art: {joint: v}}."""
        fields = {}
        if keyframe:
            fields["keyframe_name"] = keyframe
        if qpos:
            fields["per_articulation_qpos"] = qpos
        return _arrays(self.call("reset", **fields))

    def set_mode(self, mode):
        return self.call("set_mode", mode=mode)

    def set_paused(self, paused):
        return self.call("set_paused", paused=paused)

    def list_keyframes(self):
        return self.call("list_keyframes")["keyframes"]

    def set_qpos(self, articulation, qpos):
        return _arrays(self.call("set_qpos", articulation=articulation,
                                 qpos=[float(x) for x in qpos]))

    def forward(self):
        return _arrays(self.call("forward"))

    def set_twist(self, articulation, vx=0.0, vy=0.0, yaw_rate=0.0):
        """Drives the articulation's twist controller (free base): planar velocity in its heading
        frame and yaw rate, clamped to the scene's maxima; the reply gives what was applied."""
        return self.call("set_twist", articulation=articulation,
                         linear=[float(vx), float(vy), 0.0], angular=[0.0, 0.0, float(yaw_rate)])

    def fire_launcher(self, launcher):
        """Fires one of the scene's impulse launchers (name); the reply names the projectile."""
        return self.call("fire_launcher", launcher=launcher)

    def puppet(self, qpos=None, qvel=None, ctrl=None, time=None, per_articulation=None):
        """Puppet mode (set_mode("puppet") first): writes the whole model's qpos/qvel/ctrl (or
        per articulation {art: {"qpos", "qvel", "ctrl"}}) and time, runs mj_forward, returns the
        observation."""
        fields = {}
        for name, v in (("qpos", qpos), ("qvel", qvel), ("ctrl", ctrl)):
            if v is not None:
                fields[name] = [float(x) for x in v]
        if time is not None:
            fields["time"] = float(time)
        if per_articulation:
            fields["per_articulation"] = {
                art: {k: [float(x) for x in v] for k, v in parts.items()}
                for art, parts in per_articulation.items()}
        return _arrays(self.call("step", **fields))

    def get_contacts(self, max_contacts=64, **filter):
        """Active contacts (force in the contact frame); filter by body1/body2/geom1/geom2."""
        fields = {"max_contacts": max_contacts}
        if filter:
            fields["filter"] = filter
        return self.call("get_contacts", **fields)

    def set_sim_options(self, **options):
        return self.call("set_sim_options", options=options)["options"]

    def configure_controller(self, articulation, **params):
        return self.call("configure_controller", articulation=articulation, params=params)

    def set_mocap_pose(self, body, pos=None, quat=None):
        fields = {"body": body}
        if pos is not None:
            fields["pos"] = [float(x) for x in pos]
        if quat is not None:
            fields["quat"] = [float(x) for x in quat]
        return self.call("set_mocap_pose", **fields)

    # ---- Recorder, snapshots and replay (the server's recorder writes and reads the files).
    # Every `path` is a file name in the server's files folder (network.files_dir, --files-dir),
    # never a path; an existing file is replaced only with overwrite=True (which needs the
    # driver lease). The replies give the file's full path on the server.

    def recording_start(self, path=None, compress=True, sensordata=False, keyframe_interval=None,
                        max_duration=None, ring_seconds=None, overwrite=False):
        """Starts recording every physics step to the file named `path` (a fresh name when
        None); returns its full path on the server."""
        fields = {"compress": compress, "sensordata": sensordata, "overwrite": overwrite}
        for key, value in (("path", path), ("keyframe_interval", keyframe_interval),
                           ("max_duration", max_duration), ("ring_seconds", ring_seconds)):
            if value is not None:
                fields[key] = value
        return self.call("recording_start", **fields)["path"]

    def recording_stop(self):
        """Finishes the recording: {"path", "frames", "duration", "bytes", "dropped"}."""
        return self.call("recording_stop")

    def recording_save(self, path, overwrite=False):
        return self.call("recording_save", path=path, overwrite=overwrite)["path"]

    def recording_clear(self):
        return self.call("recording_clear")

    def recording_status(self):
        return self.call("recording_status")

    def snapshot_save(self, path, overwrite=False):
        """Saves the simulation's full state to the file named `path`; returns its time."""
        return self.call("snapshot_save", path=path, overwrite=overwrite)["time"]

    def snapshot_load(self, path):
        """Restores a snapshot of this model (applied before the reply); returns its time."""
        return self.call("snapshot_load", path=path)["time"]

    def replay_load(self, path):
        """Opens a recording for replay: {"session", "frames", "duration", "chunks", ...}."""
        return self.call("replay_load", path=path)

    def replay_list_sessions(self):
        return self.call("replay_list_sessions")["sessions"]

    def replay_set_active(self, session):
        return self.call("replay_set_active", session=session)

    def replay_start(self, session=None, mode="kinematic", speed=None, loop=None):
        """Plays a loaded recording through the engine (mode kinematic or resimulate)."""
        fields = {"mode": mode}
        if session is not None:
            fields["session"] = session
        if speed is not None:
            fields["speed"] = float(speed)
        if loop is not None:
            fields["loop"] = bool(loop)
        return self.call("replay_start", **fields)

    def replay_stop(self):
        return self.call("replay_stop")

    def replay_unload(self, session=None):
        """Releases a loaded recording (default: the active one), stopping its playback."""
        return self.call("replay_unload", **({} if session is None else {"session": session}))

    def cancel(self):
        """Cancels the lockstep steps this session queued; returns how many requests."""
        return self.call("cancel")["cancelled"]

    def replay_status(self):
        return self.call("replay_status")

    def model_with_assets(self, folder):
        """Writes the server's composed model and its asset files into `folder` (which must
        exist); returns the model file's path, loadable with MuJoCo there."""
        import os
        reply = self.call("hello", include_assets=True)
        mine, self.session_id = self.session_id, reply["session_id"]
        try:
            self.call("bye")  # that extra session is not needed
        finally:
            self.session_id = mine
        for name, data in reply["vfs_assets"].items():
            with open(os.path.join(folder, name), "wb") as f:
                f.write(data)
        path = os.path.join(folder, "model.xml")
        with open(path, "w") as f:
            f.write(reply["mjcf_compiled"])
        return path


# UrlabEnv (gymnasium-shaped) lives in urlab_client/env.py, UrlabVectorEnv in vector.py.
