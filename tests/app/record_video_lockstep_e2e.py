#!/usr/bin/env python3
"""End to end: `urlab record --video` in lockstep (--step-mode direct). The run waits for its
client (the video's gate must not start the simulation by itself), and the video holds one frame
per 1/30 simulated second of what the client stepped: 1 s of 2 ms steps driven 10 at a time is
30 frames.
Usage: record_video_lockstep_e2e.py URLAB_BINARY SOURCE_DIR
"""
import json
import os
import subprocess
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
from urlab_client.step import StepClient, UrlabError  # noqa: E402


def fail(message, proc=None):
    if proc is not None and proc.poll() is None:
        proc.kill()
    print("FAIL:", message)
    sys.exit(1)


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_video_lockstep_")
    announce, video = os.path.join(tmp, "announce.json"), os.path.join(tmp, "wrist.mp4")
    scene = os.path.join(SOURCE, "tests", "data", "cameras", "two_cameras.yaml")
    proc = subprocess.Popen([URLAB, "record", scene, "--video", "rig/wrist", video, "--duration",
                             "1", "--ports", "auto", "--announce", announce, "--step-mode",
                             "direct"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    deadline = time.monotonic() + 60
    while not os.path.exists(announce):
        if proc.poll() is not None or time.monotonic() > deadline:
            fail(f"no announce file: {proc.communicate()[0] if proc.poll() is not None else ''}",
                 proc)
        time.sleep(0.05)
    with open(announce) as f:
        rpc = json.load(f)["endpoints"]["rpc"]
    time.sleep(1.5)  # nobody steps: a lockstep run waits
    if proc.poll() is not None:
        fail(f"the run did not wait for its client: {proc.communicate()[0]}")
    steps = 0
    with StepClient(rpc, timeout=10.0) as c:
        if c.info["mode"] != "direct":
            fail(f"mode {c.info['mode']}", proc)
        c.set_mode("direct")
        t = c.step(n_steps=1)["time"]
        if abs(t - 0.002) > 1e-12:
            fail(f"after one step of a waiting run, time {t} (it had run by itself)", proc)
        steps = 1
        try:
            while steps < 500:
                c.step(n_steps=min(10, 500 - steps))
                steps += min(10, 500 - steps)
        except (UrlabError, TimeoutError) as e:
            fail(f"stepping stopped at {steps}: {e}", proc)
    out, _ = proc.communicate(timeout=60)
    if proc.returncode != 0 or f"video: {video} frames=30\n" not in out:
        fail(f"exit {proc.returncode}, expected 30 frames:\n{out}")
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-show_entries",
                            "stream=nb_read_frames", "-of", "csv=p=0", video],
                           capture_output=True, text=True)
    if probe.stdout.strip() != "30":
        fail(f"ffprobe counts {probe.stdout.strip()} frames")
    print("record --video in lockstep: waited for its client, 30 frames for 1 s stepped")


if __name__ == "__main__":
    main()
