"""Batched environments inside this Python process (EnvPool's way): no server, socket or shared
memory between the learner and the physics. URLab's C interface (liburlab_batch.so, built and
installed beside the `urlab` binary) runs the scene's batch on this thread and the batch's
stepping threads while the call holds no GIL.

    from urlab_client import UrlabVectorEnv
    envs = UrlabVectorEnv.in_process("examples/scenes/humanoid_pd.yaml", num_envs=64)
    obs, infos = envs.reset(seed=0)
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
    envs.close()

It is `urlab run SCENE --envs N` without the network: the same resets, seeds, next-step
autoreset, episode limit, latency and randomisation, so environment i with seed s runs the same
episode as in a batched server, and every environment runs the scene's controllers (a PD scene
takes joint targets). Several in-process batches may be open in one process (a training and an
evaluation env). The arrays a step returns are fresh (a rollout buffer may keep them).

For MuJoCo's own Python package: `model` (a mujoco.MjModel) and `data(i)` (a mujoco.MjData of
environment i now) are copies of the batch's (mj_copyModel, mj_copyData through the library:
MuJoCo 3.17's bindings wrap no mjData they did not allocate, and MjModel._from_model_ptr owns
and frees the model it wraps), for mujoco.Renderer or the bindings' functions; writing to them
changes nothing in the batch (UrlabVectorEnv.model and .data(i) give the same).

The library is found from `library=`, then $URLAB_BATCH_LIBRARY, then in the build folder of
the repository this package lives in (a fresh checkout's `tools/build.sh` output: build/, and
build-*/), then beside the `urlab` found on PATH (its own folder: a build tree; ../lib and
../lib/*: an installation), then the system's library path; the error lists every path tried.
"""
import ctypes
import glob
import os
import shutil
import threading

import numpy as np

from urlab_client.batch import BatchBackend, BatchCalls, renamed

ABI = 3  # urlab/embed/urlab_batch.h's URLAB_BATCH_ABI
_F8 = np.dtype("<f8")
_U4 = np.dtype("<u4")
_NAME = "liburlab_batch.so"

# Every integer is checked here, before ctypes (which wraps what does not fit: 2**32 + 1
# environments would be one, seed 2**64 would be 0). The limits are the library's and the step
# server's: seeds are whole numbers a double holds exactly, n_steps at most 100,000 a call.
_INT_MAX = 2 ** 31 - 1
MAX_SEED = 2 ** 53 - 1
MAX_N_STEPS = 100000
LOG_LEVELS = ("trace", "debug", "info", "warn", "error", "off")


def _whole(name, value, low, high):
    """`value` as an int in [low, high]; ValueError naming `name` and the range otherwise
    (floats, bools and strings are not whole numbers here)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name}: {value!r} is not a whole number in [{low}, {high}]")
    v = int(value)
    if not low <= v <= high:
        raise ValueError(f"{name}: {v} is not a whole number in [{low}, {high}]")
    return v


class _Options(ctypes.Structure):
    _fields_ = [("envs", ctypes.c_int), ("threads", ctypes.c_int), ("auto_reset", ctypes.c_int),
                ("max_episode_steps", ctypes.c_int), ("reset_noise", ctypes.c_double),
                ("has_seed", ctypes.c_int), ("seed", ctypes.c_uint64),
                ("log_level", ctypes.c_char_p), ("raw_actions", ctypes.c_int)]


class _Sizes(ctypes.Structure):
    _fields_ = [("envs", ctypes.c_int), ("threads", ctypes.c_int), ("nu", ctypes.c_int),
                ("nq", ctypes.c_int), ("nv", ctypes.c_int), ("nsensordata", ctypes.c_int),
                ("obs_size", ctypes.c_int), ("timestep", ctypes.c_double)]


class _Outputs(ctypes.Structure):
    _fields_ = [("obs", ctypes.c_void_p), ("done", ctypes.c_void_p), ("reset", ctypes.c_void_p),
                ("time", ctypes.c_void_p), ("episode_steps", ctypes.c_void_p),
                ("seconds", ctypes.c_double)]


def checkout_root():
    """The URLab checkout this package lives in (clients/python/urlab_client), or None."""
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
    return root if os.path.exists(os.path.join(root, "CMakeLists.txt")) else None


def repository_builds(name):
    """`name` in the build folders of the repository holding this package (clients/python/
    urlab_client in a checkout: build/ first, then build-*/), for an editable install or a
    PYTHONPATH into the checkout; [] for an installed package."""
    root = checkout_root()
    if root is None:
        return []
    return [os.path.join(root, "build", name)] + \
        sorted(glob.glob(os.path.join(root, "build-*", name)))


def library_candidates(library=None):
    """The paths tried for liburlab_batch.so, in order."""
    if library:
        return [library]
    out = []
    if os.environ.get("URLAB_BATCH_LIBRARY"):
        out.append(os.environ["URLAB_BATCH_LIBRARY"])
    out.extend(repository_builds(_NAME))
    urlab = shutil.which("urlab")
    if urlab:
        here = os.path.dirname(os.path.realpath(urlab))
        out.append(os.path.join(here, _NAME))
        out.append(os.path.join(here, "..", "lib", _NAME))
        out.extend(sorted(glob.glob(os.path.join(here, "..", "lib", "*", _NAME))))
    out.append(_NAME)  # the system's library path (ldconfig, LD_LIBRARY_PATH)
    return out


_LIB = {}


def load_library(library=None):
    """The C interface as a ctypes library (loaded once per path). Raises OSError saying where
    it looked."""
    tried = []
    for path in library_candidates(library):
        if path in _LIB:
            return _LIB[path]
        if os.sep in path and not os.path.exists(path):
            tried.append(path + " (no such file)")
            continue
        try:
            lib = ctypes.CDLL(path)  # CDLL: calls release the GIL
        except OSError as e:
            tried.append(f"{path} ({e})")
            continue
        lib.urlab_batch_abi.restype = ctypes.c_int
        if lib.urlab_batch_abi() != ABI:
            raise OSError(f"{path} has interface version {lib.urlab_batch_abi()}, this client "
                          f"speaks {ABI}: use the urlab_client of the same URLab")
        lib.urlab_batch_open.restype = ctypes.c_void_p
        lib.urlab_batch_open.argtypes = [ctypes.c_char_p, ctypes.POINTER(_Options),
                                         ctypes.c_char_p, ctypes.c_size_t]
        lib.urlab_batch_close.restype = None
        lib.urlab_batch_close.argtypes = [ctypes.c_void_p]
        lib.urlab_batch_get_sizes.argtypes = [ctypes.c_void_p, ctypes.POINTER(_Sizes)]
        lib.urlab_batch_action_bounds.argtypes = [ctypes.c_void_p, ctypes.c_void_p,
                                                  ctypes.c_void_p]
        lib.urlab_batch_actuator_names.restype = ctypes.c_size_t
        lib.urlab_batch_actuator_names.argtypes = [ctypes.c_void_p, ctypes.c_char_p,
                                                   ctypes.c_size_t]
        lib.urlab_batch_step.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                         ctypes.c_int, ctypes.POINTER(_Outputs),
                                         ctypes.c_char_p, ctypes.c_size_t]
        lib.urlab_batch_reset.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                          ctypes.c_void_p, ctypes.c_void_p,
                                          ctypes.POINTER(_Outputs), ctypes.c_char_p,
                                          ctypes.c_size_t]
        lib.urlab_batch_set_auto_reset.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.urlab_batch_mujoco_version.restype = ctypes.c_int
        lib.urlab_batch_copy_model.restype = ctypes.c_void_p
        lib.urlab_batch_copy_model.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p,
                                               ctypes.c_size_t]
        lib.urlab_batch_copy_data.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p,
                                              ctypes.c_char_p, ctypes.c_size_t]
        _LIB[path] = lib
        return lib
    raise OSError("URLab's in-process library (" + _NAME + ") was not found; tried: " +
                  "; ".join(tried) + ". Build URLab (tools/build.sh), put `urlab` on PATH, or "
                  "give library= or $URLAB_BATCH_LIBRARY")


class InProcessBatch(BatchCalls):
    """A batch of `envs` environments of `scene` in this process, with BatchClient's interface
    (UrlabVectorEnv's BatchBackend drives either): send_step() steps at once (the GIL released),
    receive_step_parts() returns the result. Calls from several threads take turns; close()
    waits for one under way. Errors in what it is given raise ValueError with
    the library's message (naming the field, or the scene file and line). raw_actions: the
    actions are the controls and the scene's controllers stay off (`urlab run --raw-actions`);
    by default every environment runs them (a PD scene takes joint targets)."""

    def __init__(self, scene, envs=1, threads=0, seed=None, max_episode_steps=0,
                 reset_noise_scale=None, auto_reset=True, frame_skip=None, library=None,
                 log_level="warn", raw_actions=False, **deprecated):
        deprecated.update(reset_noise_scale=reset_noise_scale, frame_skip=frame_skip)
        reset_noise = renamed(deprecated, "reset_noise", "reset_noise_scale", 0.0)
        frame_skip = renamed(deprecated, "n_steps", "frame_skip", 1)
        if deprecated:
            raise TypeError(f"unknown option(s) {sorted(deprecated)}")
        envs = _whole("envs", envs, 1, _INT_MAX)
        threads = _whole("threads", threads, 0, _INT_MAX)
        if seed is not None:
            seed = _whole("seed", seed, 0, MAX_SEED)
        max_episode_steps = _whole("max_episode_steps", max_episode_steps, 0, _INT_MAX)
        frame_skip = _whole("frame_skip", frame_skip, 1, MAX_N_STEPS)
        reset_noise = float(reset_noise)
        if not np.isfinite(reset_noise) or reset_noise < 0:
            raise ValueError(f"reset_noise_scale: {reset_noise} is not a finite number >= 0")
        if log_level not in LOG_LEVELS:
            raise ValueError(f"log_level: {log_level!r} is not one of {', '.join(LOG_LEVELS)}")
        self._lib = load_library(library)
        self._lock = threading.Lock()  # calls from several threads take turns
        self.endpoint = "in-process:" + str(scene)
        self.transport = "in-process"
        self.frame_skip = frame_skip
        options = _Options(envs, threads, 1 if auto_reset else 0, max_episode_steps, reset_noise,
                           seed is not None, seed or 0, log_level.encode(),
                           1 if raw_actions else 0)
        self._error = ctypes.create_string_buffer(4096)
        handle = self._lib.urlab_batch_open(os.fsencode(scene), ctypes.byref(options),
                                            self._error, len(self._error))
        if not handle:
            raise ValueError(self._error.value.decode(errors="replace"))
        self._handle = ctypes.c_void_p(handle)
        self.client = self  # as BatchClient's: the object a vector env's envs[k].client is
        sizes = _Sizes()
        self._lib.urlab_batch_get_sizes(self._handle, ctypes.byref(sizes))
        self.envs, self.nu, self.obs_size = sizes.envs, sizes.nu, sizes.obs_size
        self.threads, self.timestep = sizes.threads, sizes.timestep
        self.layout = [("qpos", 0, sizes.nq), ("qvel", sizes.nq, sizes.nv),
                       ("sensordata", sizes.nq + sizes.nv, sizes.nsensordata)]
        self.action_low = np.empty(self.nu)
        self.action_high = np.empty(self.nu)
        self._lib.urlab_batch_action_bounds(self._handle, self.action_low.ctypes.data,
                                            self.action_high.ctypes.data)
        need = self._lib.urlab_batch_actuator_names(self._handle, None, 0)
        names = ctypes.create_string_buffer(max(1, need))
        self._lib.urlab_batch_actuator_names(self._handle, names, need)
        self.actuators = [n.decode() for n in names.raw[:need].split(b"\0")[:-1]]
        self.info = {"envs": self.envs, "threads": self.threads, "nu": self.nu,
                     "obs_size": self.obs_size, "timestep": self.timestep,
                     "actuators": self.actuators, "auto_reset": bool(auto_reset),
                     "max_episode_steps": int(max_episode_steps),
                     "reset_noise": reset_noise, "raw_actions": bool(raw_actions)}
        self._out = _Outputs()
        self._result = None
        self._step_seconds = 0.0
        self._env_steps = 0
        self._busy = 0.0

    # ---- the calls
    def _fresh(self):
        n = self.envs
        obs, done = np.empty((n, self.obs_size)), np.empty(n, np.bool_)
        reset, time = np.empty(n, np.bool_), np.empty(n)
        steps = np.empty(n, _U4)
        out = self._out
        out.obs, out.done, out.reset = obs.ctypes.data, done.ctypes.data, reset.ctypes.data
        out.time, out.episode_steps = time.ctypes.data, steps.ctypes.data
        return obs, done, reset, time, steps

    def _check(self, status):
        if status != 0:
            raise ValueError(self._error.value.decode(errors="replace"))

    def _need_open(self):
        if self._handle is None:
            raise RuntimeError("this in-process batch is closed")

    def send_step(self, actions, reset=None):
        """actions: (envs, nu) float64; reset: (envs,) bool, those reset instead of stepping."""
        with self._lock:
            self._send_step(actions, reset)

    def _send_step(self, actions, reset):
        self._need_open()
        if type(actions) is not np.ndarray or actions.dtype != _F8 or \
                not actions.flags.c_contiguous:
            actions = np.ascontiguousarray(actions, dtype=_F8)
        if actions.size != self.envs * self.nu:
            raise ValueError(f"actions hold {actions.size} values, expected "
                             f"{self.envs * self.nu} ({self.envs} environments x {self.nu} "
                             "actuators)")
        flags = None
        if reset is not None and np.count_nonzero(reset):
            flags = np.ascontiguousarray(reset, dtype=np.uint8)
            if flags.size != self.envs:
                raise ValueError(f"reset holds {flags.size} flags, expected one per environment "
                                 f"({self.envs})")
        arrays = self._fresh()
        self._check(self._lib.urlab_batch_step(
            self._handle, actions.ctypes.data, None if flags is None else flags.ctypes.data,
            self.frame_skip, ctypes.byref(self._out), self._error, len(self._error)))
        self._result = arrays
        self._step_seconds = self._out.seconds
        self._busy += self._out.seconds
        self._env_steps += self.envs * self.frame_skip

    def send_reset(self, envs=None, seeds=None, auto_reset=None):
        """envs: indices (None: all); seeds: one int or None per listed environment."""
        with self._lock:
            self._send_reset(envs, seeds, auto_reset)

    def _send_reset(self, envs, seeds, auto_reset):
        self._need_open()
        if auto_reset is not None:
            self._lib.urlab_batch_set_auto_reset(self._handle, 1 if auto_reset else 0)
            self.info["auto_reset"] = bool(auto_reset)
        listed = None
        if envs is not None:
            indices = [_whole("envs", e, 0, self.envs - 1) for e in np.ravel(np.asarray(
                envs, dtype=object))]
            listed = np.ascontiguousarray(indices, dtype=np.intc)
        count = 0 if listed is None else listed.size
        if listed is not None and count == 0:
            raise ValueError("reset: an empty list of environments")
        k = self.envs if listed is None else count
        seed_values = has = None
        if seeds is not None:
            seeds = list(seeds)
            if len(seeds) != k:
                raise ValueError(f"{len(seeds)} seeds for {k} environments")
            seeds = [None if s is None else _whole("seeds", s, 0, MAX_SEED) for s in seeds]
            has = np.array([s is not None for s in seeds], dtype=np.uint8)
            seed_values = np.array([0 if s is None else int(s) for s in seeds], dtype=np.uint64)
        arrays = self._fresh()
        self._check(self._lib.urlab_batch_reset(
            self._handle, None if listed is None else listed.ctypes.data, count,
            None if seed_values is None else seed_values.ctypes.data,
            None if has is None else has.ctypes.data, ctypes.byref(self._out), self._error,
            len(self._error)))
        self._result = arrays

    # ---- MuJoCo's Python bindings (the `mujoco` package) on the batch's environments
    def _mujoco(self):
        import mujoco
        ours = self._lib.urlab_batch_mujoco_version()
        if mujoco.mj_version() != ours:
            raise RuntimeError(f"the batch runs MuJoCo {ours}, the `mujoco` module here is "
                               f"{mujoco.mj_version()} ({mujoco.__version__}): their structs "
                               "differ (install the pinned mujoco of tools/requirements.txt)")
        if not hasattr(mujoco.MjModel, "_from_model_ptr"):
            raise RuntimeError(f"mujoco {mujoco.__version__} cannot take a model from a "
                               "pointer (MjModel._from_model_ptr)")
        return mujoco

    def model_of(self, env=0):
        """A mujoco.MjModel: a copy (mj_copyModel) of environment `env`'s model (its own when
        the scene randomises, else the one they all share), owned by Python. Changing it changes
        nothing in the batch."""
        mujoco = self._mujoco()
        env = _whole("env", env, 0, self.envs - 1)
        with self._lock:
            self._need_open()
            ptr = self._lib.urlab_batch_copy_model(self._handle, env, self._error,
                                                   len(self._error))
            if not ptr:
                raise ValueError(self._error.value.decode(errors="replace"))
        return mujoco.MjModel._from_model_ptr(ptr)  # the wrapper frees it (mj_deleteModel)

    @property
    def model(self):
        """The batch's model as a mujoco.MjModel (environment 0's: model_of), copied once."""
        if getattr(self, "_model", None) is None:
            self._model = self.model_of(0)
        return self._model

    def data(self, env=0, out=None):
        """Environment `env`'s mjData now, as a mujoco.MjData of `model`: a copy (mj_copyData)
        of all of it, taken between steps: state, contacts, and the positions and sensors as the
        last step computed them (at its start, as mj_step does: the observation's sensordata is
        this; mj_forward on the copy brings them to its qpos). Writing to it changes nothing in
        the batch; call again after a step. out: an MjData (of `model`, or of a model of the
        same sizes) to fill instead of a new one."""
        mujoco = self._mujoco()
        env = _whole("env", env, 0, self.envs - 1)
        model = self.model
        if out is None:
            out = mujoco.MjData(model)
        elif not isinstance(out, mujoco.MjData):
            raise TypeError(f"out: a mujoco.MjData, not {type(out).__name__}")
        else:
            mine = (model.nq, model.nv, model.nu, model.na, model.nbody, model.nsensordata)
            theirs = out.model
            if mine != (theirs.nq, theirs.nv, theirs.nu, theirs.na, theirs.nbody,
                        theirs.nsensordata):
                raise ValueError("out: an MjData of a model of other sizes than the batch's")
        with self._lock:
            self._need_open()
            self._check(self._lib.urlab_batch_copy_data(self._handle, env, out._address,
                                                        self._error, len(self._error)))
        return out

    @property
    def n_steps(self):  # the old name of frame_skip
        return self.frame_skip

    def _parts(self):
        obs, done, _, time, steps = self._result
        return obs, done, time, steps

    def receive_step_parts(self):
        return self._parts()

    def receive_reset_parts(self):
        return self._parts()

    def _dict(self):
        obs, done, reset, time, steps = self._result
        return {"obs": obs, "done": done, "reset": reset, "time": time, "episode_steps": steps,
                "step_seconds": self._step_seconds}

    def receive_step(self):
        return self._dict()

    def receive_reset(self):
        return self._dict()

    def call(self, op):
        """batch_info's counters (env_steps, busy_seconds: the stepping thread's time on
        steps), as a batched server answers them."""
        if op != "batch_info":
            raise ValueError(f"an in-process batch answers batch_info only (not {op})")
        return dict(self.info, env_steps=self._env_steps, busy_seconds=self._busy)

    def drop(self):
        self.close()

    def close(self):
        lock = getattr(self, "_lock", None)
        if lock is None:  # the constructor failed before it
            return
        with lock:  # after a call under way on another thread, never during it
            handle, self._handle = getattr(self, "_handle", None), None
            if handle is not None:
                self._lib.urlab_batch_close(handle)

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown: the library may be gone
            pass


def in_process_backend(scene, num_envs, threads=0, seed=None, frame_skip=None, reward_fn=None,
                       terminated_fn=None, max_episode_steps=None, server_max_episode_steps=0,
                       reset_noise_scale=None, library=None, log_level="warn", task=None,
                       raw_actions=False, **deprecated):
    """UrlabVectorEnv's batched backend over one InProcessBatch (UrlabVectorEnv.in_process)."""
    deprecated.update(frame_skip=frame_skip, reset_noise_scale=reset_noise_scale)
    frame_skip = renamed(deprecated, "n_steps", "frame_skip", None)
    reset_noise_scale = renamed(deprecated, "reset_noise", "reset_noise_scale", None)
    if deprecated:
        raise TypeError(f"unknown option(s) {sorted(deprecated)}")
    if frame_skip is None:
        frame_skip = task.frame_skip if task is not None else 1
    if reset_noise_scale is None:
        reset_noise_scale = task.reset_noise_scale if task is not None else 0.0
    batch = InProcessBatch(scene, envs=num_envs, threads=threads, seed=seed,
                           max_episode_steps=server_max_episode_steps,
                           reset_noise_scale=reset_noise_scale, frame_skip=frame_skip,
                           library=library, log_level=log_level, raw_actions=raw_actions)
    try:
        return BatchBackend([batch], reward_fn=reward_fn, terminated_fn=terminated_fn,
                            max_episode_steps=max_episode_steps, task=task)
    except BaseException:
        batch.close()
        raise


__all__ = ["InProcessBatch", "in_process_backend", "load_library", "library_candidates",
           "repository_builds", "checkout_root"]
