#!/usr/bin/env python3
"""The bundled robots composed into one scene (a Go2 with its floor, an H1, the arm and a second
Go2), run by the real `urlab`, against the pinned `mujoco` Python package stepping the MJB that
`urlab compile` wrote for the same scene:

1. the MJB loads in the package, with every name under its articulation's prefix and each
   articulation's `home` keyframe as `{name}_home`;
2. `urlab record` plays the scene; its recording, exported with `urlab replay --export-npz`, is
   URLab's trajectory (qpos, qvel and the controls of every step);
3. the package, started as URLab starts (each articulation in its keyframe) and given the same
   controls, steps the MJB through the same qpos and qvel, bit for bit, at every recorded step.

Usage: robot_scene_python_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

import mujoco
import numpy as np

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
ROBOTS = os.path.join(SOURCE, "tests", "data", "mjcf", "robots")
ARTICULATIONS = [("dog", "go2/scene.xml", 0.0, True), ("h1", "h1/h1.xml", 2.0, False),
                 ("arm", "arm/arm.xml", 4.0, False), ("dog2", "go2/go2.xml", -2.0, False)]


def urlab(*args):
    run = subprocess.run([URLAB, "--log-level", "warn", *args], capture_output=True, text=True,
                         timeout=300)
    if run.returncode != 0:
        sys.exit(f"urlab {' '.join(args)} failed ({run.returncode}):\n{run.stdout}{run.stderr}")
    return run.stdout


def main():
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "robots.yaml")
        with open(scene, "w") as f:
            f.write("articulations:\n")
            for name, file, x, world in ARTICULATIONS:
                f.write(f"  - {{name: {name}, mjcf: {os.path.join(ROBOTS, file)}, "
                        f"pos: [{x}, 0, 0], keyframe: home"
                        f"{'' if world else ', include_world: false'}}}\n")
        mjb = os.path.join(tmp, "robots.mjb")
        urlab("compile", scene, "--save-mjb", mjb)
        model = mujoco.MjModel.from_binary_path(mjb)
        for name, _, _, _ in ARTICULATIONS:
            if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, f"{name}_home") < 0:
                failures.append(f"no keyframe {name}_home in the MJB")
        joints = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
        for j in joints:
            if j and not any(j.startswith(n + "_") for n, _, _, _ in ARTICULATIONS):
                failures.append(f"joint {j!r} carries no articulation's prefix")

        rec = os.path.join(tmp, "robots.urrec")
        urlab("record", scene, "-o", rec, "--no-network", "--no-cameras", "--max-speed",
              "--duration", "0.5")
        npz = os.path.join(tmp, "robots.npz")
        urlab("replay", rec, "--export-npz", npz)
        arrays = np.load(npz)
        qpos, qvel, ctrl = arrays["qpos"], arrays["qvel"], arrays["ctrl"]
        rows = qpos.shape[0]
        if qpos.shape[1] != model.nq or qvel.shape[1] != model.nv or ctrl.shape[1] != model.nu:
            sys.exit(f"the recording's sizes {qpos.shape[1]}/{qvel.shape[1]}/{ctrl.shape[1]} are "
                     f"not the MJB's nq/nv/nu {model.nq}/{model.nv}/{model.nu}")
        if rows < 100:
            failures.append(f"only {rows} recorded steps")

        # The package starts where URLab starts (each articulation's joints in its own
        # keyframe, everything else at rest) and steps the MJB with URLab's recorded controls.
        data = mujoco.MjData(model)
        for name, _, _, _ in ARTICULATIONS:
            key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, f"{name}_home")
            for j, joint in enumerate(joints):
                if not (joint or "").startswith(name + "_"):
                    continue
                width = {0: 7, 1: 4}.get(int(model.jnt_type[j]), 1)
                a, v = model.jnt_qposadr[j], model.jnt_dofadr[j]
                data.qpos[a:a + width] = model.key_qpos[key][a:a + width]
                nv = {0: 6, 1: 3}.get(int(model.jnt_type[j]), 1)
                data.qvel[v:v + nv] = model.key_qvel[key][v:v + nv]
        times = arrays["time"]
        worst, first_diff = 0.0, None
        step = 0
        for k in range(rows):
            while step < round(times[k] / model.opt.timestep):
                data.ctrl[:] = ctrl[k]
                mujoco.mj_step(model, data)
                step += 1
            diff = max(float(np.max(np.abs(data.qpos - qpos[k]))),
                       float(np.max(np.abs(data.qvel - qvel[k]))))
            worst = max(worst, diff)
            if first_diff is None and not (np.array_equal(data.qpos, qpos[k]) and
                                           np.array_equal(data.qvel, qvel[k])):
                first_diff = k
        print(f"{rows} recorded steps (nq {model.nq}, nu {model.nu}), t = {times[0]:.4f} to "
              f"{times[-1]:.4f} s: largest |difference| {worst:.3g}; first row differing in its "
              f"bits: {first_diff}")
        if first_diff is not None:
            failures.append(f"the package's trajectory leaves URLab's at row {first_diff} "
                            f"(largest difference {worst:.3g})")
    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
