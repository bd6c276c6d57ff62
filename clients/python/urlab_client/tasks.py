"""The bundled tasks as gymnasium environment ids (registered when urlab_client is imported).

    import gymnasium
    import urlab_client  # noqa: F401  (registers URLab/ArmReach-v0, ...)

    env = gymnasium.make("URLab/ArmReach-v0")            # one environment: its own urlab server
    envs = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=16,
                              vectorization_mode="vector_entry_point")   # in this process

A task is a scene of examples/scenes with what makes it learnable: actions in -1..1 (scaled to
each action's range: a joint target under the scene's PD or gait controller, which runs in every
environment as it does for a client of `urlab run SCENE`), a flat float32 observation with finite bounds, a reward and a
termination, all computed over the batch's own parts (qpos, qvel, sensordata of the whole
model), vectorised over environments. Both ways run the same task on the same physics:
`gymnasium.make(id)` starts `urlab run SCENE --envs 1` and drives its one environment through the
batch operations (a server process of its own, so gymnasium's sync and async vector envs work
too); `gymnasium.make_vec(id, num_envs=N)` steps N environments in this process
(UrlabVectorEnv.in_process: URLab's C library; several can be open at once, a training and an
evaluation env). make(id) reset with seed s runs the episode environment i of make_vec(id) reset with
seed s - i runs, bit for bit, for the same actions.

- URLab/ArmReach-v0 (arm_reach.yaml): reward minus the tip's distance (m) to a target drawn
  at reset; terminated within 5 cm of it, or diverged.
- URLab/HumanoidStand-v0 (humanoid_pd.yaml): 1 per step alive; terminated when the torso is
  below 1 m, or diverged.
- URLab/QuadrupedWalk-v0 (quadruped_walk.yaml): the base's forward velocity (m/s) + 1 alive;
  terminated when the base is below 0.17 m, or diverged.
- URLab/Go2Walk-v0 (go2_network.yaml): the same, the base below 0.16 m.

The scenes are the repository's (found from this package's place in a checkout, or
$URLAB_SOURCE_DIR); the urlab binary as urlab_client.tasks.find_urlab says, the in-process
library as urlab_client.inproc.load_library says.
"""
import math
import os
import shutil
import signal

import gymnasium
import numpy as np
from gymnasium import spaces

from urlab_client.inproc import checkout_root, repository_builds

OBS_LIMIT = 1000.0  # the observations' bounds (clipped to them; a healthy simulation stays within)


def source_dir():
    """The URLab checkout: $URLAB_SOURCE_DIR, else the repository holding this package."""
    if os.environ.get("URLAB_SOURCE_DIR"):
        return os.environ["URLAB_SOURCE_DIR"]
    return checkout_root() or os.getcwd()


def find_urlab(urlab=None):
    """The urlab binary: `urlab`, $URLAB_BINARY, the checkout's build folders, `urlab` on PATH.
    Raises FileNotFoundError listing the paths tried."""
    tried = []
    for path in ([urlab] if urlab else []) + \
            ([os.environ["URLAB_BINARY"]] if os.environ.get("URLAB_BINARY") else []) + \
            repository_builds("urlab") + [shutil.which("urlab") or "urlab (on PATH)"]:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
        tried.append(path)
        if urlab:
            break
    raise FileNotFoundError("no urlab binary; tried: " + "; ".join(tried) + ". Build URLab "
                            "(tools/build.sh), put `urlab` on PATH, or give urlab= or "
                            "$URLAB_BINARY")


class Task:
    """One task: its scene and timing, and its observation, reward and termination over a batch
    of environments (obs: {"qpos", "qvel", "sensordata"} arrays, one row per environment;
    state: the task's own arrays for those rows, drawn by reset_env)."""

    name = None             # the id is URLab/{name}-v0
    scene = None            # in examples/scenes
    frame_skip = 1          # physics steps per env step
    max_episode_steps = 1000
    reset_noise_scale = 0.01  # uniform noise on qpos and qvel at every reset

    def check(self, sizes, actuators):
        """Raises ValueError when the scene is not the one this task was written for."""

    def scene_path(self):
        path = os.path.join(source_dir(), "examples", "scenes", self.scene)
        if not os.path.exists(path):
            raise FileNotFoundError(f"task {self.name}: no scene {path} (urlab_client finds the "
                                    "scenes in the checkout it lives in, or $URLAB_SOURCE_DIR)")
        return path

    def observation_size(self, sizes):
        raise NotImplementedError

    def observation_space(self, sizes):
        return spaces.Box(-OBS_LIMIT, OBS_LIMIT, shape=(self.observation_size(sizes),),
                          dtype=np.float32)

    def observation(self, obs, state):
        return np.clip(self.features(obs, state), -OBS_LIMIT, OBS_LIMIT).astype(np.float32)

    def features(self, obs, state):
        raise NotImplementedError

    def new_state(self, n):
        return {}

    def reset_env(self, state, i, rng):
        """Draws environment i's task state (its rows of `state`) from its generator."""

    def reward(self, obs, actions, state):
        raise NotImplementedError

    def terminated(self, obs, state):
        return np.zeros(len(obs["qpos"]), dtype=bool)


class ArmReach(Task):
    """The servo arm brings its tip to a target in its plane, in front of it, drawn at every
    reset (examples/python/learn_reach.py's task): observation [qpos, qvel, tip, target,
    target - tip], reward minus the distance (m), terminated within `success` of it."""

    name, scene = "ArmReach", "arm_reach.yaml"
    frame_skip, max_episode_steps = 25, 100   # 0.05 s per step, 5 s
    shoulder = np.array([0.0, 1.1])  # (x, z) in the arm's plane
    success = 0.05

    def check(self, sizes, actuators):
        if sizes.get("sensordata", 0) < 5:
            raise ValueError(f"task {self.name}: expects the tip's position at sensordata[2:5]")

    def observation_size(self, sizes):
        return sizes["qpos"] + sizes["qvel"] + 9

    def new_state(self, n):
        return {"target": np.tile([0.5, 0.0, 1.1], (n, 1))}

    def reset_env(self, state, i, rng):
        # 0.3 to 0.7 m from the shoulder, from 57 degrees below its height to 69 above.
        radius, angle = rng.uniform(0.3, 0.7), rng.uniform(-1.0, 1.2)
        x, z = self.shoulder + radius * np.array([math.cos(angle), math.sin(angle)])
        state["target"][i] = (x, 0.0, z)

    @staticmethod
    def tip(obs):
        return obs["sensordata"][:, 2:5]

    def features(self, obs, state):
        tip, target = self.tip(obs), state["target"]
        return np.concatenate([obs["qpos"], obs["qvel"], tip, target, target - tip], axis=1)

    def distance(self, obs, state):
        return np.linalg.norm(state["target"] - self.tip(obs), axis=1)

    def reward(self, obs, actions, state):
        return -self.distance(obs, state)

    def terminated(self, obs, state):
        return self.distance(obs, state) < self.success


class Legged(Task):
    """A robot on a free base: observation [qpos without the base's x and y, qvel, sensordata],
    terminated when the base's height drops below `fallen`."""

    fallen = 0.0
    forward_weight = 0.0   # reward: forward_weight * the base's x velocity + alive
    alive = 1.0

    def check(self, sizes, actuators):
        if sizes["qpos"] < 7:
            raise ValueError(f"task {self.name}: expects a free base (qpos[0:7])")

    def observation_size(self, sizes):
        return sizes["qpos"] - 2 + sizes["qvel"] + sizes["sensordata"]

    def features(self, obs, state):
        return np.concatenate([obs["qpos"][:, 2:], obs["qvel"], obs["sensordata"]], axis=1)

    def reward(self, obs, actions, state):
        return self.forward_weight * obs["qvel"][:, 0] + self.alive

    def terminated(self, obs, state):
        return ~(obs["qpos"][:, 2] >= self.fallen)   # NaN: fallen too


class HumanoidStand(Legged):
    """MuJoCo's humanoid keeps standing (it starts upright and falls unless its motors hold it):
    1 per step alive, terminated when the torso is below 1 m (gymnasium's Humanoid's rule)."""

    name, scene = "HumanoidStand", "humanoid_pd.yaml"
    frame_skip, max_episode_steps = 5, 1000
    fallen = 1.0


class QuadrupedWalk(Legged):
    """The bundled quadruped (position servos: actions are joint targets) walks forward: reward
    the base's forward velocity + 1 alive, terminated when the base is below 0.17 m (it stands
    at 0.285)."""

    name, scene = "QuadrupedWalk", "quadruped_walk.yaml"
    frame_skip, max_episode_steps = 10, 1000   # 0.02 s per step, 20 s
    fallen, forward_weight = 0.17, 1.0


class Go2Walk(Legged):
    """The Go2-style dog (torque motors) walks forward: reward the base's forward velocity + 1
    alive, terminated when the base is below 0.16 m (it stands at 0.27)."""

    name, scene = "Go2Walk", "go2_network.yaml"
    frame_skip, max_episode_steps = 10, 1000
    fallen, forward_weight = 0.16, 1.0


TASKS = {t.name: t for t in (ArmReach(), HumanoidStand(), QuadrupedWalk(), Go2Walk())}


def task_of(task):
    if isinstance(task, Task):
        return task
    if task not in TASKS:
        raise KeyError(f"no task {task!r} (have {sorted(TASKS)})")
    return TASKS[task]


class UrlabTaskEnv(gymnasium.Env):
    """One environment of a task (what gymnasium.make(id) gives): `urlab run SCENE --envs 1`
    started here, driven through the batch operations (the same physics and task as the
    in-process vector env), stopped by close(). urlab: the binary (find_urlab's order).
    frame_skip, reset_noise_scale: the task's unless given. StepClient's options (timeout,
    shared_memory) pass through."""

    metadata = {"render_modes": []}

    def __init__(self, task, urlab=None, frame_skip=None, reset_noise_scale=None,
                 render_mode=None, **client_options):
        from urlab_client.batch import BatchBackend
        from urlab_client.cluster import start_server
        if render_mode is not None:
            raise ValueError(f"render_mode {render_mode!r}: URLab's task environments render "
                             "nothing (`urlab view` shows a scene)")
        self.task = task_of(task)
        self._proc = self._backend = None
        noise = self.task.reset_noise_scale if reset_noise_scale is None else reset_noise_scale
        self._proc, announced = start_server(
            find_urlab(urlab), self.task.scene_path(),
            ["--no-cameras", "--envs", "1", "--threads", "1", "--reset-noise", str(float(noise))])
        try:
            self._backend = BatchBackend.connect(announced["endpoints"]["rpc"], task=self.task,
                                                 frame_skip=frame_skip, **client_options)
        except BaseException:
            self._stop()
            raise
        self.observation_space = self._backend.single_observation_space
        self.action_space = self._backend.single_action_space

    @staticmethod
    def _info(infos):
        return {k: v[0] for k, v in infos.items() if not k.startswith("_") and infos["_" + k][0]}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self._need_open()
        obs, infos = self._backend.reset(None if seed is None else [seed], options,
                                         rngs=[self.np_random])
        return obs[0], self._info(infos)

    def step(self, action):
        self._need_open()
        obs, rewards, terminated, truncated, infos = self._backend.step(
            np.asarray(action, dtype=np.float64).reshape(1, -1))
        return obs[0], float(rewards[0]), bool(terminated[0]), bool(truncated[0]), \
            self._info(infos)

    @property
    def model(self):
        """The scene's model as a mujoco.MjModel, from the MJB its server sent at hello (a copy:
        changing it changes nothing in the environment; urlab_client.env.model_from_hello)."""
        if getattr(self, "_mj_model", None) is None:
            from urlab_client.env import model_from_hello
            self._need_open()
            self._mj_model = model_from_hello(self._backend.clients[0].client.info)
        return self._mj_model

    def _need_open(self):
        if self._backend is None:
            raise RuntimeError(f"this {self.task.name} environment is closed")

    def _stop(self):
        proc, self._proc = self._proc, None
        if proc is not None and proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=30)
            except Exception:  # noqa: BLE001
                proc.kill()
                proc.wait()

    def close(self):
        backend, self._backend = getattr(self, "_backend", None), None
        try:
            if backend is not None:
                backend.close()
        finally:
            self._stop()

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass


def make_vector_env(task, num_envs=1, max_episode_steps=None, render_mode=None, **options):
    """The vector entry point (gymnasium.make_vec(id, num_envs, vectorization_mode=
    "vector_entry_point")): UrlabVectorEnv.in_process over num_envs environments of the task.
    options: UrlabVectorEnv.in_process's (threads, frame_skip, reset_noise_scale, library...)."""
    from urlab_client.vector import UrlabVectorEnv
    if render_mode is not None:
        raise ValueError(f"render_mode {render_mode!r}: URLab's task environments render nothing")
    task = task_of(task)
    return UrlabVectorEnv.in_process(task.scene_path(), num_envs, task=task,
                                     max_episode_steps=max_episode_steps, **options)


def register():
    """Registers URLab/{name}-v0 for every task (once)."""
    for name, task in TASKS.items():
        env_id = f"URLab/{name}-v0"
        if env_id in gymnasium.registry:
            continue
        gymnasium.register(id=env_id, entry_point="urlab_client.tasks:UrlabTaskEnv",
                           vector_entry_point="urlab_client.tasks:make_vector_env",
                           max_episode_steps=task.max_episode_steps, kwargs={"task": name})


__all__ = ["Task", "TASKS", "UrlabTaskEnv", "make_vector_env", "register", "find_urlab"]
