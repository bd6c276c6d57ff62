"""UrlabEnv: one articulation of a URLab step server as a gymnasium environment.

    from urlab_client import UrlabEnv
    with UrlabEnv("arm", endpoint="tcp://127.0.0.1:5559", max_episode_steps=200) as env:
        obs, info = env.reset(seed=0)
        for _ in range(200):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            if terminated or truncated:
                obs, info = env.reset()

UrlabEnv is a gymnasium.Env (gymnasium's wrappers and env checker apply), its spaces
gymnasium.spaces.

- The server runs in lockstep (direct mode) while the env holds the driver lease; close() (or
  leaving the `with` block) says bye, which releases the lease and returns the server to the
  scene's step mode at once (not after the lease timeout).
- action_space: one value per actuator in discovery order, bounded by each actuator's
  target_range (the joint's range when a PD or keyframe controller takes position targets, the
  ctrlrange otherwise; unbounded is infinite).
- observation_space: a Dict of the articulation's observation at the level asked for (minimal:
  qpos, qvel; standard: + ctrl, act, sensors; full: + xpos, xquat, actuator_force), and with
  `cameras` the images of those camera streams (rendered from the step's own state).
- reset(seed=s) resets the server to the same initial state (the scene's, or `keyframe`) and
  draws any initial noise (`reset_noise_scale`: uniform on hinge and slide joints) from a
  generator seeded with s, so the same seed and actions give the same episode.
- reward_fn(obs, action, info) -> float and terminated_fn(obs, info) -> bool are the task (or
  override compute_reward / compute_terminated in a subclass); max_episode_steps truncates.
"""
from collections import OrderedDict

import numpy as np

import gymnasium
from gymnasium import spaces

from urlab_client.step import StepClient, decode_observation

UNBOUNDED = 100.0  # hello's target_range uses -100/100 for "no limit"


def _space_of(value):
    """The space an observation value lives in (numbers unbounded; images by their dtype)."""
    if isinstance(value, dict):
        subs = OrderedDict((k, _space_of(v)) for k, v in value.items())
        subs = OrderedDict((k, s) for k, s in subs.items() if s is not None)
        return spaces.Dict(subs)
    arr = np.asarray(value)
    if arr.dtype == np.uint8:
        return spaces.Box(0, 255, shape=arr.shape, dtype=np.uint8)
    if not np.issubdtype(arr.dtype, np.number):
        return None
    dtype = np.float32 if arr.dtype == np.float32 else np.float64
    if np.issubdtype(arr.dtype, np.integer):
        dtype = arr.dtype
        info = np.iinfo(dtype)
        return spaces.Box(info.min, info.max, shape=arr.shape, dtype=dtype)
    return spaces.Box(-np.inf, np.inf, shape=arr.shape, dtype=dtype)


def _conform(value, space):
    """`value` restricted to the keys and dtypes of `space` (a key the server adds later, such
    as a twist once a twist controller is attached, is left out)."""
    if isinstance(space, spaces.Dict):
        return OrderedDict((k, _conform(value[k], s)) for k, s in space.items())
    return np.asarray(value, dtype=space.dtype).reshape(space.shape)


def model_from_hello(info):
    """The server's model as a mujoco.MjModel, loaded from the MJB its hello_ok carries
    (`mjb`; MJB files load only in the MuJoCo release that wrote them: the server's
    `mujoco_version` must be this `mujoco` module's)."""
    import mujoco
    theirs = info.get("mujoco_version")
    if theirs is not None and theirs != mujoco.__version__:
        raise RuntimeError(f"the server runs MuJoCo {theirs}, the `mujoco` module here is "
                           f"{mujoco.__version__}: its MJB does not load here")
    mjb = info.get("mjb")
    if mjb is None and info.get("mjb_base64") is not None:
        import base64
        mjb = base64.b64decode(info["mjb_base64"])
    if mjb is None:
        raise RuntimeError("the server sent no model (no mjb in hello_ok)")
    return mujoco.MjModel.from_binary_path("model.mjb", {"model.mjb": bytes(mjb)})


class UrlabEnv(gymnasium.Env):
    """One articulation of a URLab step server in lockstep (see the module's docstring).

    articulation: its name in the scene. endpoint: the step server (tcp://, ipc://).
    frame_skip: physics steps per env step. keyframe: the reset state (None: the scene's
    initial state). observations: minimal | standard | full. cameras: camera stream names
    ("cam" or "art/cam") whose images join the observation under "cameras". require: the
    server's identity to insist on ({"scene", "instance", "server_session"}, e.g. from an
    announce file). client_options: passed to StepClient (timeout, ...).
    """

    metadata = {"render_modes": []}

    def __init__(self, articulation, endpoint="tcp://127.0.0.1:5559", frame_skip=1,
                 keyframe=None, observations="standard", cameras=None, reward_fn=None,
                 terminated_fn=None, max_episode_steps=None, reset_noise_scale=0.0,
                 require=None, **client_options):
        if frame_skip < 1:
            raise ValueError(f"frame_skip must be at least 1, got {frame_skip}")
        self.articulation = articulation
        self.endpoint = endpoint
        self.frame_skip = int(frame_skip)
        self.keyframe = keyframe
        self.observations = observations
        self.cameras = list(cameras or [])
        self.reward_fn = reward_fn
        self.terminated_fn = terminated_fn
        self.max_episode_steps = max_episode_steps
        self.reset_noise_scale = float(reset_noise_scale)
        self.client = StepClient(endpoint, observations=observations, require=require,
                                 **client_options)
        try:
            self._describe()
            self.client.set_mode("direct")
            # The observation's layout, from the current state (mj_forward changes nothing the
            # next reset does not set again).
            first = self._observation(
                decode_observation(self.client.call("forward", **self._obs_fields())))
            self.observation_space = _space_of(first)
        except BaseException:
            self.client.close()
            raise
        self._elapsed = 0
        self._needs_reset = True

    # ---- the articulation, from hello_ok
    def _describe(self):
        arts = {a["name"]: a for a in self.client.info["articulations"]}
        if self.articulation not in arts:
            raise KeyError(f"no articulation '{self.articulation}' (have {sorted(arts)})")
        art = self._art = arts[self.articulation]
        self.actuators = [a["name"] for a in art["actuators"]]
        low = np.array([a["target_range"][0] for a in art["actuators"]], dtype=np.float64)
        high = np.array([a["target_range"][1] for a in art["actuators"]], dtype=np.float64)
        low[low <= -UNBOUNDED] = -np.inf
        high[high >= UNBOUNDED] = np.inf
        self.action_space = spaces.Box(low, high, shape=(len(self.actuators),), dtype=np.float64)
        # Joints that take initial noise (one qpos value each).
        self._noisy_joints = [j for j in art["joints"] if j["type"] in ("hinge", "slide")]
        self.server = {k: self.client.info.get(k) for k in ("scene", "instance", "server_session")}

    def _obs_fields(self):
        fields = {"observations": self.observations}
        if self.cameras:
            fields["include_cameras"] = {c: "sync" for c in self.cameras}
        return fields

    def _observation(self, reply):
        obs = OrderedDict((k, v) for k, v in reply["per_articulation"][self.articulation].items())
        if self.cameras:
            frames = OrderedDict()
            got = reply.get("cameras", {})
            for name in self.cameras:
                # "stream" of this articulation ("top", "top/depth"), or "art/stream".
                frame = got.get(self.articulation, {}).get(name)
                if frame is None and "/" in name:
                    art, stream = name.split("/", 1)
                    frame = got.get(art, {}).get(stream)
                frames[name] = (frame or {}).get("image")
                if frames[name] is None:
                    raise RuntimeError(f"camera stream '{name}' sent no image")
            obs["cameras"] = frames
        space = getattr(self, "observation_space", None)
        return obs if space is None else _conform(obs, space)

    @staticmethod
    def _info(reply):
        return {"time": float(reply["time"]), "step": int(reply["step"])}

    # ---- the task: override these or pass reward_fn / terminated_fn
    def compute_reward(self, obs, action, info):
        return float(self.reward_fn(obs, action, info)) if self.reward_fn else 0.0

    def compute_terminated(self, obs, info):
        return bool(self.terminated_fn(obs, info)) if self.terminated_fn else False

    # ---- gymnasium's API
    def reset(self, *, seed=None, options=None):
        """Resets the server (keyframe, or options["keyframe"]) and returns (obs, info).
        options: {"keyframe": name, "qpos": {joint: value}, "noise_scale": s}."""
        self.send_reset(options, seed=seed)
        return self.receive_reset()

    def step(self, action):
        self.send_step(action)
        return self.receive_step()

    @property
    def model(self):
        """The server's whole model (every articulation of the scene) as a mujoco.MjModel,
        loaded once from the MJB the server sent at hello (model_from_hello): for MuJoCo's
        Python tools (mujoco.Renderer with an MjData of it, the bindings' functions). A copy:
        changing it changes nothing on the server."""
        if getattr(self, "_mj_model", None) is None:
            self._need_open()
            self._mj_model = model_from_hello(self.client.info)
        return self._mj_model

    def close(self):
        """Says bye: the lease is released and the server returns to the scene's step mode."""
        client, self.client = getattr(self, "client", None), None
        if client is not None:
            client.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    def _need_open(self):
        if self.client is None:
            raise RuntimeError(f"this UrlabEnv ({self.endpoint}) is closed")

    # ---- the same in two halves, so a vector env sends to every server, then gathers
    def send_reset(self, options=None, seed=None):
        self._need_open()
        if seed is not None:
            gymnasium.Env.reset(self, seed=seed)  # the generator of the initial noise
        options = dict(options or {})
        keyframe = options.pop("keyframe", self.keyframe)
        qpos = dict(options.pop("qpos", {}) or {})
        scale = float(options.pop("noise_scale", self.reset_noise_scale))
        if options:
            raise ValueError(f"unknown reset option(s) {sorted(options)}: keyframe, qpos, "
                             "noise_scale")
        self._reset_plan = (keyframe, qpos, scale)
        fields = self._obs_fields()
        if keyframe:
            fields["keyframe_name"] = keyframe
        if qpos and scale <= 0:  # one request; with noise, qpos is added after the base state
            fields["per_articulation_qpos"] = {self.articulation: qpos}
        self.client.send_request("reset", **fields)

    def receive_reset(self):
        reply = decode_observation(self.client.receive_reply("reset"))
        keyframe, qpos, scale = self._reset_plan
        if scale > 0:
            # Noise around the reset state, drawn from the env's generator (seeded by reset).
            base = reply["per_articulation"][self.articulation]["qpos"]
            values = {}
            for j in self._noisy_joints:
                v = qpos.get(j["name"], base[self._qpos_index(j)])
                values[j["name"]] = float(v + self.np_random.uniform(-scale, scale))
            fields = self._obs_fields()
            if keyframe:
                fields["keyframe_name"] = keyframe
            fields["per_articulation_qpos"] = {self.articulation: values}
            reply = decode_observation(self.client.call("reset", **fields))
        self._elapsed = 0
        self._needs_reset = False
        return self._observation(reply), self._info(reply)

    def _qpos_index(self, joint):
        # The articulation's qpos in the observation is its joints' values in discovery order.
        index = 0
        for j in self._art["joints"]:
            if j["name"] == joint["name"]:
                return index
            index += j["qpos_width"]
        raise KeyError(joint["name"])

    def send_step(self, action):
        self._need_open()
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != self.action_space.shape:
            raise ValueError(f"action of shape {a.shape} for {self.action_space.shape} "
                             f"(one value per actuator: {self.actuators})")
        self._last_action = a
        fields = self._obs_fields()
        fields["n_steps"] = self.frame_skip
        fields["per_articulation"] = {self.articulation: {"ctrl": [float(x) for x in a]}}
        self.client.send_request("step", **fields)

    def receive_step(self):
        reply = decode_observation(self.client.receive_reply("step"))
        obs, info = self._observation(reply), self._info(reply)
        self._elapsed += 1
        reward = self.compute_reward(obs, self._last_action, info)
        terminated = self.compute_terminated(obs, info)
        truncated = bool(self.max_episode_steps is not None and
                         self._elapsed >= self.max_episode_steps)
        return obs, reward, terminated, truncated, info
