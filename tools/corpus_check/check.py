#!/usr/bin/env python3
"""Checks URLab's model loading against the `mujoco` Python package of the same release.

For every MJCF file under the folders given (default: the project's own models): when the
pinned `mujoco` package loads it, `urlab compile FILE --save-mjb OUT.mjb` must load it too, and
the MJB URLab wrote, loaded back by the Python package, must have the same sizes and step
bit-identically to the package's own load of the XML (qpos and qvel after 200 steps from qpos0).
A file the package refuses is skipped (not a model: an include fragment, a deliberately broken
file); a file URLab refuses for a limit of MuJoCo's attachment it documents (docs/engine.md:
tuples) is counted apart. Prints one line per file and a summary; exits 1 when any file differs
or URLab refuses a file MuJoCo loads for another reason.

    .venv/bin/python tools/corpus_check/check.py [--urlab build/urlab] [--steps 200] DIR...

MuJoCo's own corpus (model/ and test/ of the pinned release) is a folder to pass here once it is
brought onto the machine; it is not part of the repository.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
# Refusals docs/engine.md documents (what MuJoCo's mjs_attach cannot carry).
KNOWN_REFUSALS = ("does not carry tuples",)
SIZES = ("nq", "nv", "nu", "na", "nbody", "njnt", "ngeom", "nsite", "ntendon", "nsensor",
         "nsensordata", "nmesh", "nkey", "neq", "nflex", "nplugin")


def load_xml(path):
    try:
        return mujoco.MjModel.from_xml_path(path), None
    except Exception as e:  # noqa: BLE001 - any refusal by MuJoCo
        return None, str(e).splitlines()[0]


def rollout(model, steps):
    data = mujoco.MjData(model)
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return data.qpos.copy(), data.qvel.copy()


def check(urlab, path, steps, tmp):
    reference, why = load_xml(path)
    if reference is None:
        return "skip", f"MuJoCo refuses it: {why}"
    mjb = os.path.join(tmp, "out.mjb")
    if os.path.exists(mjb):
        os.remove(mjb)
    run = subprocess.run([urlab, "--log-level", "error", "compile", path, "--save-mjb", mjb],
                         capture_output=True, text=True, timeout=600)
    if run.returncode != 0:
        message = (run.stdout + run.stderr).strip().splitlines()[-1]
        if any(known in message for known in KNOWN_REFUSALS):
            return "known", "refused as documented: " + message
        return "FAIL", "urlab refuses it: " + message
    ours = mujoco.MjModel.from_binary_path(mjb)
    for s in SIZES:
        if getattr(ours, s) != getattr(reference, s):
            return "FAIL", f"{s}: {getattr(ours, s)} vs MuJoCo's {getattr(reference, s)}"
    q1, v1 = rollout(reference, steps)
    q2, v2 = rollout(ours, steps)
    if not (np.array_equal(q1, q2, equal_nan=True) and np.array_equal(v1, v2, equal_nan=True)):
        return "FAIL", f"qpos/qvel differ after {steps} steps"
    return "ok", f"nq={reference.nq} nu={reference.nu}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dirs", nargs="*", help="folders of MJCF files (searched recursively)")
    parser.add_argument("--urlab", default=os.path.join(ROOT, "build", "urlab"))
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args()
    dirs = args.dirs or [os.path.join(ROOT, d) for d in
                         ("examples/models", "tests/data/mjcf/corpus", "tests/data/mjcf/robots",
                          "tests/data/mjcf/dialect3x", "tests/data/mjcf/bridge3x")]
    files = sorted(os.path.join(d, f) for top in dirs for d, _, fs in os.walk(top) for f in fs
                   if f.endswith(".xml"))
    counts = {"ok": 0, "skip": 0, "known": 0, "FAIL": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for i, path in enumerate(files, 1):
            status, detail = check(args.urlab, path, args.steps, tmp)
            counts[status] += 1
            print(f"[{i}/{len(files)}] {status:5} {os.path.relpath(path, ROOT)}: {detail}",
                  flush=True)
    print(f"corpus: {counts['ok']} identical, {counts['FAIL']} failed, {counts['known']} refused "
          f"as documented, {counts['skip']} refused by MuJoCo {mujoco.__version__} "
          f"(of {len(files)} files)")
    return 1 if counts["FAIL"] else 0


if __name__ == "__main__":
    sys.exit(main())
