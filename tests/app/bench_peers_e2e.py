#!/usr/bin/python3
"""`urlab bench peers` with tiny settings: every peer runs at N = 1 and 2, each prints its rows,
and the key=value lines the issue asks for are there and finite (ours_over_envpool, or
envpool=unavailable with ours_over_nearest; ours_over_rollout and its spread). URLab and
mujoco.rollout step the same trajectories: their last states agree (physics_max_abs_diff).
No absolute time is asserted. A bad --skip and a missing model are refused before anything runs.
Usage: bench_peers_e2e.py URLAB_BINARY
"""
import math
import subprocess
import sys

URLAB = sys.argv[1]
failures = []


def expect(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what, flush=True)


def main():
    help_text = subprocess.run([URLAB, "bench", "peers", "--help"], capture_output=True,
                               text=True, timeout=60).stdout
    for option in ("--envs", "--threads", "--seconds", "--repeats", "--skip", "--frame-skip"):
        expect(option in help_text, f"--help names {option}")

    bad = subprocess.run([URLAB, "bench", "peers", "--skip", "nobody"], capture_output=True,
                         text=True, timeout=60)
    expect(bad.returncode != 0, f"--skip nobody is refused (exit {bad.returncode})")
    bad = subprocess.run([URLAB, "bench", "peers", "/nonexistent/model.xml"],
                         capture_output=True, text=True, timeout=60)
    expect(bad.returncode != 0, f"a missing model is refused (exit {bad.returncode})")

    run = subprocess.run([URLAB, "bench", "peers", "--envs", "1,2", "--threads", "2",
                          "--seconds", "0.2", "--repeats", "2"], capture_output=True, text=True,
                         timeout=900)
    print(run.stdout)
    print(run.stderr[-3000:], file=sys.stderr)
    expect(run.returncode == 0, f"bench peers exits 0 (got {run.returncode})")
    expect("[peers]" in run.stderr, "progress lines on stderr")

    rows = {}
    kv = {}
    for line in run.stdout.splitlines():
        if "=" in line:
            key, value = line.split("=", 1)
            kv[key] = value
            continue
        parts = line.split()
        if len(parts) == 7 and parts[1].isdigit():  # peer N threads median min max cpu
            rows[(parts[0], int(parts[1]))] = [float(x) for x in parts[3:6]]

    def finite(key):
        try:
            v = float(kv[key])
        except (KeyError, ValueError):
            return None
        return v if math.isfinite(v) else None

    envpool_ran = "envpool" not in kv
    row_names = ["gym_sync", "gym_async", "rollout", "urlab_physics", "urlab_physics_wall",
                 "urlab_inproc", "urlab_server"] + (["envpool"] if envpool_ran else [])
    for name in row_names:
        for n in (1, 2):
            r = rows.get((name, n))
            expect(r is not None, f"a row for {name} N={n}")
            if r is not None:
                med, lo, hi = r
                expect(0 < lo <= med <= hi and math.isfinite(hi),
                       f"{name} N={n}: 0 < min <= median <= max ({r})")
            v = finite(f"{name}_n{n}_env_steps_per_s")
            expect(v is not None and v > 0, f"{name}_n{n}_env_steps_per_s is a positive number")

    if envpool_ran:
        for key in ("ours_over_envpool", "server_over_envpool"):
            v = finite(key)
            expect(v is not None and v > 0, f"{key}= is a positive number ({kv.get(key)})")
        expect(kv.get("envpool_version"), "envpool_version= is printed")
    else:
        expect(kv["envpool"].startswith("unavailable reason="), "envpool=unavailable reason=...")
        v = finite("ours_over_nearest")
        expect(v is not None and v > 0, "ours_over_nearest= is a positive number")
    for key in ("ours_over_rollout", "ours_over_rollout_min", "ours_over_rollout_max",
                "ours_over_rollout_wall", "ours_over_rollout_n1"):
        v = finite(key)
        expect(v is not None and v > 0, f"{key}= is a positive number ({kv.get(key)})")
    lo, med, hi = (finite("ours_over_rollout_min"), finite("ours_over_rollout"),
                   finite("ours_over_rollout_max"))
    if None not in (lo, med, hi):
        expect(lo <= med <= hi, "ours_over_rollout lies within its min and max")
    # The same model, initial states and actions: the same trajectories, bit for bit.
    for key in ("physics_max_abs_diff", "physics_max_abs_diff_n1"):
        expect(finite(key) == 0.0, f"{key}= is 0 ({kv.get(key)})")
    for key in ("mujoco", "timestep", "frame_skip", "model"):
        expect(key in kv, f"{key}= is printed")

    if failures:
        print(f"{len(failures)} failure(s)")
        return 1
    print("bench peers: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
