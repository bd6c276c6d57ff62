#!/usr/bin/python3
"""End to end: UrlabVectorEnv.in_process (URLab's C library loaded by this Python process, no
server) against a batched server (`urlab run SCENE --envs N`, its own process, shared memory):

- the same seeds and actions give the same observations, flags and times, bit for bit, through a
  truncation and gymnasium's next-step autoreset (the server's environment 0 is its engine's own
  simulation; in-process every environment is the batch's);
- gymnasium's contract: the spaces contain the observations, the same seed gives the same
  episode, fresh arrays every step (a rollout buffer may keep them);
- bad input raises with the library's message: a missing scene named, actions of the wrong
  shape, a NaN action naming its environment and actuator, a
  library that is not there (the paths tried), a step after close(), close() on another thread
  while one steps.
Usage: inproc_e2e.py URLAB_BINARY SOURCE_DIR LIBRARY
"""
import os
import sys
import tempfile
import threading
import time

import numpy as np

URLAB, SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:4])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import UrlabVectorEnv  # noqa: E402
from urlab_client.inproc import InProcessBatch  # noqa: E402
from urlab_process import PROCS, check, raises, start_announced, stop_all  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "scenes", "humanoid_pd.yaml")
ENVS, STEPS, LIMIT = 4, 25, 10


def run(envs, actions):
    """Observations, flags and times of a reset with seed 7, then the given actions."""
    obs, infos = envs.reset(seed=7)
    out = [(np.concatenate([obs["qpos"], obs["qvel"]], axis=1).copy(), infos["time"].copy())]
    for a in actions:
        obs, rewards, terminated, truncated, infos = envs.step(a)
        out.append((np.concatenate([obs["qpos"], obs["qvel"]], axis=1), infos["time"],
                    terminated, truncated, rewards))
    return out


def main():
    rng = np.random.default_rng(3)
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--max-speed", "--envs",
                                      str(ENVS), "--threads", "2", "--reset-noise", "0.05",
                                      "--max-episode-steps", str(LIMIT), duration=86400)
    PROCS.append(proc)
    served = UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"], shared_memory=True)
    local = UrlabVectorEnv.in_process(SCENE, ENVS, threads=2, library=LIBRARY,
                                      reset_noise_scale=0.05,
                                      server_max_episode_steps=LIMIT)
    check(local.envs[0].transport == "in-process", f"transport {local.envs[0].transport}")
    check(local.single_action_space == served.single_action_space,
          f"action spaces {local.single_action_space} / {served.single_action_space}")
    check(local.single_observation_space == served.single_observation_space,
          "observation spaces differ")
    nu = local.single_action_space.shape[0]
    low, high = local.single_action_space.low, local.single_action_space.high
    actions = [rng.uniform(low, high, size=(ENVS, nu)) for _ in range(STEPS)]

    a, b = run(served, actions), run(local, actions)
    for t, (x, y) in enumerate(zip(a, b)):
        for k, (u, v) in enumerate(zip(x, y)):
            check(np.array_equal(u, v), f"step {t}, part {k}: in-process differs from the server")
    # The server's --max-episode-steps truncated at step LIMIT; the next step reset them.
    check(all(b[LIMIT][3]) and not any(b[LIMIT - 1][3]), "no truncation at the episode limit")
    check(np.all(b[LIMIT + 1][1] == 0), f"autoreset times {b[LIMIT + 1][1]}")
    served.close()

    # gymnasium's contract on the in-process env.
    obs, _ = local.reset(seed=11)
    check(local.observation_space.contains(obs), "reset obs outside the observation space")
    first = obs["qpos"].copy()
    kept = []
    for a in actions[:5]:
        obs, *_ = local.step(a)
        check(local.observation_space.contains(obs), "step obs outside the observation space")
        kept.append(obs["qpos"])
    check(not np.array_equal(kept[0], kept[-1]), "a step's arrays changed under a later step")
    obs, _ = local.reset(seed=11)
    check(np.array_equal(obs["qpos"], first), "the same seed gave another start")
    obs, _ = local.reset(seed=12)
    check(not np.array_equal(obs["qpos"], first), "another seed gave the same start")

    # Bad input.
    raises(ValueError, "actions of shape", lambda: local.step(np.zeros((ENVS, nu + 1))))
    bad = np.zeros((ENVS, nu))
    bad[2, 5] = np.nan
    raises(ValueError, "environment 2, actuator 5 is not a finite number",
           lambda: local.step(bad))
    raises(ValueError, "seeds: -3 is not", lambda: local.reset(seed=[-3, 0, 0, 0]))
    raises(ValueError, "seeds: 9007199254740992 is not",
           lambda: local.reset(seed=[2 ** 53, 0, 0, 0]))
    second = InProcessBatch(SCENE, envs=1, library=LIBRARY)  # beside the first: fine
    second.close()
    raises(OSError, "/no/such/liburlab_batch.so (no such file)",
           lambda: InProcessBatch(SCENE, library="/no/such/liburlab_batch.so"))
    local.close()
    raises(ValueError, "/no/such/scene.yaml",
           lambda: InProcessBatch("/no/such/scene.yaml", envs=2, library=LIBRARY))
    tmp = tempfile.mkdtemp(prefix="urlab_inproc_")
    broken = os.path.join(tmp, "broken.yaml")
    with open(broken, "w") as f:
        f.write("articulations:\n  - name: h\n    mjcf: " + os.path.join(SOURCE, "examples/models/humanoid.xml") + "\n"
                "    controller: {type: pd, kp: -3}\n")
    raises(ValueError, "broken.yaml:4", lambda: InProcessBatch(broken, envs=2, library=LIBRARY))
    gone = InProcessBatch(SCENE, envs=2, library=LIBRARY)
    gone.close()
    raises(RuntimeError, "closed", lambda: gone.step(np.zeros((2, nu))))
    # close() on another thread while one steps: the step under way ends, the next one raises.
    racer = InProcessBatch(SCENE, envs=2, library=LIBRARY)
    errors = []

    def steps():
        try:
            for _ in range(1000000):
                racer.step(np.zeros((2, nu)))
        except RuntimeError as e:
            errors.append(str(e))

    thread = threading.Thread(target=steps)
    thread.start()
    time.sleep(0.3)
    racer.close()
    thread.join(30)
    check(not thread.is_alive() and errors and "closed" in errors[0],
          f"a step racing close(): {errors}")
    # A context manager releases the batch: another one opens after it.
    with UrlabVectorEnv.in_process(SCENE, 2, library=LIBRARY) as envs:
        envs.reset(seed=0)
    with UrlabVectorEnv.in_process(SCENE, 2, library=LIBRARY) as envs:
        envs.step(np.zeros((2, nu)))
    print("inproc_e2e: ok")


if __name__ == "__main__":
    try:
        main()
    finally:
        stop_all()
