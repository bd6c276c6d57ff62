#!/usr/bin/python3
"""Issue 38, case 7: the in-process binding (urlab_client.inproc) range-checks every integer
before ctypes sees it. ctypes wraps them silently: envs=2**32+1 opened one environment,
seed=2**64 became 0, max_episode_steps=2**32 meant no limit, reset(envs=[2**32]) reset
environment 0; log_level 'bogus' was accepted and n_steps=10**7 ran for a minute in one call (the
server caps n_steps at 100,000). Each raises ValueError naming the field and its range, before
anything is opened or stepped; good values at the edges still work.
Usage: inproc_ranges_e2e.py SOURCE_DIR LIBRARY
"""
import os
import sys

import numpy as np

SOURCE, LIBRARY = (os.path.abspath(a) for a in sys.argv[1:3])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
from urlab_client.inproc import InProcessBatch  # noqa: E402

SCENE = os.path.join(SOURCE, "examples", "scenes", "humanoid_pd.yaml")
failures = []


def raises(text, fn, *needles):
    try:
        fn()
    except ValueError as e:
        for n in (text,) + needles:
            if n not in str(e):
                failures.append(f"expected {n!r} in {e!r}")
        return
    except Exception as e:  # noqa: BLE001
        failures.append(f"{text}: raised {type(e).__name__}: {e}, not ValueError")
        return
    failures.append(f"{text}: accepted")


def opened(**kw):
    b = InProcessBatch(SCENE, library=LIBRARY, **kw)
    b.close()
    failures.append(f"opened with {kw}")


def main():
    raises("envs", lambda: opened(envs=2 ** 32 + 1), "[1, ")
    raises("envs", lambda: opened(envs=2.5))
    raises("threads", lambda: opened(envs=1, threads=2 ** 32))
    raises("seed", lambda: opened(envs=1, seed=2 ** 64), "9007199254740991")
    raises("seed", lambda: opened(envs=1, seed=2 ** 53), "9007199254740991")
    raises("max_episode_steps", lambda: opened(envs=1, max_episode_steps=2 ** 32))
    raises("max_episode_steps", lambda: opened(envs=1, max_episode_steps=-1))
    raises("log_level", lambda: opened(envs=1, log_level="bogus"), "warn")
    raises("frame_skip", lambda: opened(envs=1, frame_skip=10 ** 7), "100000")
    raises("frame_skip", lambda: opened(envs=1, frame_skip=0))
    raises("reset_noise_scale", lambda: opened(envs=1, reset_noise_scale=float("nan")))

    b = InProcessBatch(SCENE, envs=2, seed=2 ** 53 - 1, max_episode_steps=2 ** 31 - 1,
                       frame_skip=100000 // 100000, library=LIBRARY)
    try:
        nu = b.nu
        b.reset()
        before = b.receive_reset()
        raises("envs", lambda: b.send_reset(envs=[2 ** 32]), "[0, 1]")
        raises("envs", lambda: b.send_reset(envs=[-1]), "[0, 1]")
        raises("seeds", lambda: b.send_reset(envs=[0], seeds=[2 ** 64]), "9007199254740991")
        b.send_step(np.zeros((2, nu)))
        b.receive_step()
        b.send_reset(envs=[1], seeds=[2 ** 53 - 1])
        after = b.receive_reset()
        if after is None or before is None:
            failures.append("no reset result")
    finally:
        b.close()
    if failures:
        for f in failures:
            print("FAIL:", f)
        sys.exit(1)
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
