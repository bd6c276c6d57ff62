#!/usr/bin/env python3
"""End to end: MuJoCo's own Python bindings (the pinned `mujoco`) on URLab's environments.

- the in-process vector env's `model` is a mujoco.MjModel of the batch's model (same sizes,
  timestep, masses), and `data(i)` a mujoco.MjData holding environment i's mjData after a step:
  its qpos, qvel and sensordata are the batch's observation row, bit for bit, for every i;
- `mujoco.Renderer` draws environment 0 from it (MUJOCO_GL: osmesa unless set), and the picture
  changes when the arm moved;
- the bindings compute on it: mj_jacBody's linear Jacobian times qvel is the body's velocity
  (a finite difference of mj_kinematics' positions), after mj_forward on the copy;
- it is a copy: writing to it or stepping it changes nothing in the batch; data(i, out=d)
  refills an MjData; a bad index, an MjData of another model and a closed env are refused;
- `gymnasium.make(id).unwrapped.model`, `UrlabEnv.model` and a vector env over a batched
  server's `model` (from the MJB of the server's hello) are the same model; data(i) over servers
  says it needs an in-process env.
Usage: mujoco_interop_e2e.py URLAB_BINARY SOURCE_DIR LIBRARY
"""
import os
import sys

import numpy as np

URLAB, SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:4])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
os.environ["URLAB_BINARY"] = URLAB
os.environ["URLAB_BATCH_LIBRARY"] = LIBRARY
os.environ.setdefault("MUJOCO_GL", "osmesa")  # no display here; EGL needs a device
import gymnasium  # noqa: E402
import mujoco  # noqa: E402

import urlab_client  # noqa: E402,F401
from urlab_client import UrlabEnv, UrlabVectorEnv  # noqa: E402
from urlab_process import PROCS, check, raises, start_announced, stop_all  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "scenes", "arm_reach.yaml")


def in_process():
    envs = UrlabVectorEnv.in_process(SCENE, 3, threads=2, seed=7)
    model = envs.model
    check(isinstance(model, mujoco.MjModel), f"model is {type(model)}")
    batch = envs.envs[0]
    sizes = dict((name, size) for name, _, size in batch.layout)
    check((model.nq, model.nv, model.nu, model.nsensordata) ==
          (sizes["qpos"], sizes["qvel"], batch.nu, sizes["sensordata"]),
          f"model sizes {model.nq, model.nv, model.nu, model.nsensordata} vs {sizes}")
    check(model.opt.timestep == batch.timestep, "the model's timestep is the batch's")
    check(envs.model is model, "model is copied once")

    obs, _ = envs.reset(seed=3)
    d0 = envs.data(0)
    picture = {}
    renderer = mujoco.Renderer(model, 96, 128)
    renderer.update_scene(d0)
    picture["start"] = renderer.render().copy()
    actions = np.tile(np.array([[0.9, -0.9]]), (3, 1)) * batch.action_high
    for _ in range(40):
        obs, *_ = envs.step(actions)
    for i in range(3):
        d = envs.data(i)
        check(np.array_equal(d.qpos, obs["qpos"][i]), f"env {i}: qpos {d.qpos} vs "
              f"{obs['qpos'][i]}")
        check(np.array_equal(d.qvel, obs["qvel"][i]), f"env {i}: qvel")
        check(np.array_equal(d.sensordata, obs["sensordata"][i]), f"env {i}: sensordata")
    print(f"data(i): qpos, qvel and sensordata of all 3 environments are the observation's, "
          f"bit for bit (env 0 qpos {np.round(obs['qpos'][0], 3)})")

    d0 = envs.data(0)
    renderer.update_scene(d0)
    picture["moved"] = renderer.render().copy()
    check(picture["moved"].shape == (96, 128, 3), f"image {picture['moved'].shape}")
    check(picture["moved"].std() > 1.0, "the rendered image is not blank")
    changed = np.mean(np.any(picture["moved"] != picture["start"], axis=2))
    check(changed > 0.002, f"the picture did not change when the arm moved ({changed:.4f})")
    renderer.close()
    print(f"mujoco.Renderer drew environment 0 (96x128; {changed:.1%} of its pixels changed as "
          "the arm moved)")

    # The bindings compute on the copy: the body's Jacobian against a finite difference.
    mujoco.mj_forward(model, d0)
    body = max(b for b in range(model.nbody) if model.body_dofnum[b] > 0)  # the last link
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_jacBody(model, d0, jacp, jacr, body)
    moved = envs.data(0)
    eps = 1e-7
    moved.qpos[:] = d0.qpos + eps * d0.qvel  # hinges only: qpos and qvel have the same layout
    mujoco.mj_kinematics(model, moved)
    velocity = (moved.xpos[body] - d0.xpos[body]) / eps
    check(np.allclose(jacp @ d0.qvel, velocity, atol=1e-5),
          f"J qvel {jacp @ d0.qvel} vs the finite difference {velocity}")
    check(np.linalg.norm(velocity) > 1e-3, "the arm moves")
    print(f"mj_jacBody on data(0): J qvel = {np.round(jacp @ d0.qvel, 4)} m/s, the finite "
          "difference's")

    # A copy: writing to it, stepping it, changes nothing in the batch.
    before = envs.data(1)
    scribble = envs.data(1)
    scribble.qpos[:] = 1.0
    for _ in range(10):
        mujoco.mj_step(model, scribble)
    after = envs.data(1)
    check(np.array_equal(after.qpos, before.qpos) and after.time == before.time,
          "writing to a copy changed the batch")
    refill = mujoco.MjData(model)
    check(envs.data(2, out=refill) is refill and np.array_equal(refill.qpos, obs["qpos"][2]),
          "data(2, out=d) fills d")
    raises(ValueError, "not a whole number in [0, 2]", lambda: envs.data(3))
    other = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><body><freejoint/><geom size='.1'/></body></worldbody></mujoco>")
    raises(ValueError, "other sizes", lambda: envs.data(0, out=mujoco.MjData(other)))
    raises(TypeError, "a mujoco.MjData", lambda: envs.data(0, out=np.zeros(3)))
    envs.close()
    raises(RuntimeError, "closed", lambda: envs.data(0))
    check(envs.model is model and model.nq == 2, "the model copy outlives the batch")
    print("data(i) is a copy (writes and steps stay out of the batch); out=, bad input and a "
          "closed env handled")
    return model


def over_server(in_process_model):
    env = gymnasium.make("URLab/ArmReach-v0")
    try:
        model = env.unwrapped.model
        check(isinstance(model, mujoco.MjModel), f"model is {type(model)}")
        check((model.nq, model.nv, model.nu, model.nbody) ==
              (in_process_model.nq, in_process_model.nv, in_process_model.nu,
               in_process_model.nbody), "the server's model has the batch's sizes")
        check(np.array_equal(model.body_mass, in_process_model.body_mass) and
              model.opt.timestep == in_process_model.opt.timestep,
              "the server's model is the batch's (masses, timestep)")
    finally:
        env.close()
    print("gymnasium.make(id).unwrapped.model: the server's MJB, the same model as in process")
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras")
    PROCS.append(proc)
    rpc = announced["endpoints"]["rpc"]
    with UrlabEnv("arm", endpoint=rpc) as env:
        model = env.model
        check(np.array_equal(model.body_mass, in_process_model.body_mass) and
              model.nq == in_process_model.nq, "UrlabEnv.model is the batch's model")
    proc.terminate()
    proc.wait()
    proc, announced = start_announced(URLAB, SCENE, "--no-cameras", "--envs", "2")
    PROCS.append(proc)
    with UrlabVectorEnv.over_batch(announced["endpoints"]["rpc"]) as envs:
        check(np.array_equal(envs.model.body_mass, in_process_model.body_mass),
              "over_batch's model is the batch's model")
        raises(NotImplementedError, "in-process", lambda: envs.data(0))
    proc.terminate()
    proc.wait()
    print("UrlabEnv.model and over_batch(...).model: the same model from the server's MJB")


def main():
    try:
        model = in_process()
        over_server(model)
    finally:
        stop_all()
    print("mujoco_interop_e2e: ok")


if __name__ == "__main__":
    main()
