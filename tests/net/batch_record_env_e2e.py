#!/usr/bin/python3
"""End to end: `urlab run SCENE --envs 4 --record-env 2 --record FILE` records environment 2.

A real batched server driven through UrlabVectorEnv.over_batch with different actions per
environment, episodes ended by --max-episode-steps and reset by the next step (gymnasium's
autoreset, a reset command in the recorded environment), then stopped with SIGTERM:
- `urlab replay FILE --check` re-simulates the recording bit for bit;
- the recording is environment 2's: its last recorded qpos is, bit for bit, environment 2's last
  observation (and not environment 0's, which got other actions);
- `--record-env 4` with `--envs 4` exits 1 before simulating, naming the flag;
- a scene with `latency:` and `randomize:` runs with `--envs 2`, every environment observing
  with the delay and drawing its own gravity.
Usage: batch_record_env_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import UrlabVectorEnv  # noqa: E402
from urlab_process import fail, start_announced  # noqa: E402

ENVS, RECORDED, STEPS = 4, 2, 40


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_record_env_")
    scene = os.path.join(tmp, "arm.yaml")
    model = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")
    with open(scene, "w") as f:
        f.write(f"articulations:\n  - name: arm\n    mjcf: {model}\n")
    rec = os.path.join(tmp, "env2.urrec")

    # A recorded environment that does not exist: refused before anything runs.
    r = subprocess.run([URLAB, "run", scene, "--envs", str(ENVS), "--record-env", str(ENVS),
                        "--ports", "auto", "--no-cameras", "--duration", "5"],
                       capture_output=True, text=True, timeout=120)
    if r.returncode != 1 or "--record-env" not in r.stderr:
        fail(f"--record-env {ENVS} of --envs {ENVS}: exit {r.returncode}\n{r.stderr}")

    # A scene with latency: and randomize: serves every environment with them: each observes
    # with the delay (the state it reset to until the first release) and draws its own gravity.
    other = os.path.join(tmp, "latency.yaml")
    with open(other, "w") as f:
        f.write(f"seed: 2\narticulations:\n  - name: arm\n    mjcf: {model}\n"
                "    latency:\n      observation: {delay_steps: 3}\n"
                "randomize:\n  gravity:\n    z: {uniform: [-5, 5]}\n")
    proc, announced = start_announced(URLAB, other, "--no-cameras", "--max-speed", "--envs", "2",
                                      duration=86400)
    try:
        envs = UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"])
        first, _ = envs.reset(seed=3)
        first = np.array(first["qpos"])
        nu = envs.single_action_space.shape[0]
        after = [np.array(envs.step(np.full((2, nu), 0.5 * np.sin(0.2 * t)))[0]["qpos"])
                 for t in range(60)]
        envs.close()
    finally:
        proc.terminate()
        proc.wait(timeout=60)
    if not np.array_equal(after[0], first) or not np.array_equal(after[2], first):
        fail(f"latency with --envs 2: the first observations are not the reset state\n"
             f"{first}\n{after[0]}\n{after[2]}")
    if np.array_equal(after[3], first):
        fail("latency with --envs 2: the fourth observation is still the reset state")
    if np.array_equal(after[-1][0], after[-1][1]):
        fail(f"randomize with --envs 2: both environments moved alike\n{after[-1]}")

    proc, announced = start_announced(
        URLAB, scene, "--no-cameras", "--max-speed", "--envs", str(ENVS), "--threads", "2",
        "--record-env", str(RECORDED), "--record", rec, "--reset-noise", "0.05",
        "--max-episode-steps", "15")
    try:
        envs = UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"])
        nu = envs.single_action_space.shape[0]
        obs, _ = envs.reset(seed=7)
        resets = 0
        for t in range(STEPS):
            i = np.arange(ENVS)[:, None]
            j = np.arange(nu)[None, :]
            obs, _, terminated, truncated, _ = envs.step(np.sin(0.5 * t + 0.9 * i + 1.3 * j))
            resets += int(truncated[RECORDED])
        last = {k: np.array(v) for k, v in obs.items()}
        envs.close()
    finally:
        proc.terminate()
        proc.wait(timeout=60)
    if resets < 2:
        fail(f"environment {RECORDED} ended {resets} episodes, expected at least 2")
    if np.array_equal(last["qpos"][0], last["qpos"][RECORDED]):
        fail("environments 0 and 2 ended in the same state: the test shows nothing")

    r = subprocess.run([URLAB, "replay", rec, "--check"], capture_output=True, text=True,
                       timeout=300)
    if r.returncode != 0:
        fail(f"replay --check of the recording of environment {RECORDED}: exit {r.returncode}\n"
             f"{r.stdout}{r.stderr}")
    npz = os.path.join(tmp, "env2.npz")
    # The last episode: the recording's time goes back at each reset (one segment each).
    r = subprocess.run([URLAB, "replay", rec, "--export-npz", npz, "--segment", str(resets + 1)],
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        fail(f"replay --export-npz: exit {r.returncode}\n{r.stdout}{r.stderr}")
    recorded = np.load(npz)["qpos"]
    if not np.array_equal(recorded[-1], last["qpos"][RECORDED]):
        fail(f"the recording's last qpos {recorded[-1]} is not environment {RECORDED}'s "
             f"{last['qpos'][RECORDED]}")
    print(f"recorded environment {RECORDED}: {len(recorded)} rows, {resets} resets; "
          "replay --check: identical")


if __name__ == "__main__":
    main()
