#!/usr/bin/python3
"""End to end: the security review's network cases against a real `urlab run` process on
loopback (ephemeral ports): the process stays up, nothing is written where it must not be, the
error is the right one, and lease takeovers do not flood its log. Also the files folder's
command-line flag and scene key, with their errors.

Usage: network_hardening_e2e.py URLAB_BINARY SOURCE_DIR
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
import zmq  # noqa: E402
from urlab_client import StepClient, UrlabError  # noqa: E402
from urlab_process import fail, start_urlab  # noqa: E402


def expect_error(code, fn, proc):
    try:
        fn()
    except UrlabError as e:
        if e.code != code:
            fail(f"expected {code}, got {e.code}: {e}", proc)
        return str(e)
    fail(f"expected {code}, the request succeeded", proc)


def raw_json(endpoint, text, timeout_ms=10000):
    ctx = zmq.Context.instance()
    s = ctx.socket(zmq.REQ)
    s.setsockopt(zmq.LINGER, 0)
    s.setsockopt(zmq.RCVTIMEO, timeout_ms)
    s.connect(endpoint)
    try:
        s.send(text.encode())
        return json.loads(s.recv())
    except zmq.Again:
        return {"op": "timeout"}
    finally:
        s.close()


def stop(proc):
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        fail("urlab did not stop on SIGINT", proc)
    if proc.returncode not in (0, 130):
        fail(f"urlab exited with {proc.returncode} (a signal kills with a negative code)")
    return err


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_harden_")
    model = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")
    with open(model) as f:
        mjcf_text = f.read()
    local_model = os.path.join(tmp, "arm.xml")
    with open(local_model, "w") as f:
        f.write(mjcf_text)
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "w") as f:
        f.write("""control_source: network
network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "tcp://127.0.0.1:*"
  files_dir: .
articulations:
  - {name: arm, mjcf: arm.xml, controller: {type: pd, kp: 100, kv: 5}}
""")
    # The scene's files folder is its own folder: its inputs are there to be protected.
    proc, endpoints = start_urlab(URLAB, scene)
    rpc = endpoints[3]
    try:
        # Case 1: a JSON seq nested 20,000 deep (40 KB) used to kill the process with SIGSEGV.
        deep = '{"op": "hello", "seq": ' + "[" * 20000 + "]" * 20000 + "}"
        r = raw_json(rpc, deep)
        if r.get("code") != "bad_request" or proc.poll() is not None:
            fail(f"deep JSON seq: {str(r)[:200]}, process {proc.poll()}", proc)
        with StepClient(rpc) as c, StepClient(rpc) as other:
            # Case 3: no paths; never the scene's inputs; never over a file without overwrite.
            expect_error("bad_file_name", lambda: c.snapshot_save(local_model), proc)
            expect_error("bad_file_name", lambda: c.snapshot_save("../arm.xml"), proc)
            expect_error("file_is_input", lambda: c.snapshot_save("arm.xml", overwrite=True),
                         proc)
            expect_error("file_is_input", lambda: c.snapshot_save("scene.yaml", overwrite=True),
                         proc)
            with open(local_model) as f:
                if f.read() != mjcf_text:
                    fail("the scene's MJCF was written", proc)
            c.snapshot_save("state.urrec")
            expect_error("file_exists", lambda: other.snapshot_save("state.urrec"), proc)
            c.step()  # c drives
            expect_error("not_driver", lambda: other.snapshot_save("state.urrec", overwrite=True),
                         proc)
            # A FIFO where the recording's .part would go: refused, nobody blocked.
            os.mkfifo(os.path.join(tmp, "trap.urrec.part"))
            t0 = time.monotonic()
            message = expect_error("path_not_writable", lambda: c.recording_start("trap.urrec"),
                                   proc)
            if "FIFO" not in message:
                fail(f"FIFO refusal does not say why: {message}", proc)
            other.list_keyframes()
            print(f"FIFO refused in {time.monotonic() - t0:.3f} s; the others are answered")
            # Case 7: two clients taking the lease from each other with force.
            t0 = time.monotonic()
            n = 0
            while time.monotonic() - t0 < 2.0:
                c.step(force=True)
                other.step(force=True)
                n += 2
            flood_seconds = time.monotonic() - t0
        if proc.poll() is not None:
            fail("urlab died", proc)
    finally:
        if proc.poll() is None:
            err = stop(proc)
        else:
            fail(f"urlab exited early with {proc.returncode}", proc)
    takeovers = err.count("took the lease")
    if takeovers > 2 + flood_seconds:
        fail(f"{takeovers} takeover lines for {n} forced steps in {flood_seconds:.1f} s")
    print(f"{n} forced steps in {flood_seconds:.1f} s: {takeovers} takeover line(s) logged")

    # The flag and the scene key: errors name the problem (the key with file:line).
    not_a_folder = os.path.join(tmp, "plain.txt")
    with open(not_a_folder, "w") as f:
        f.write("x")
    r = subprocess.run([URLAB, "run", scene, "--duration", "1", "--files-dir", not_a_folder],
                       capture_output=True, text=True, timeout=60)
    if r.returncode == 0 or "not a folder" not in r.stderr + r.stdout:
        fail(f"--files-dir on a file: exit {r.returncode}: {r.stderr}{r.stdout}")
    bad_scene = os.path.join(tmp, "bad.yaml")
    with open(bad_scene, "w") as f:
        f.write(f"""network:
  files_dir: plain.txt
articulations:
  - {{name: arm, mjcf: arm.xml}}
""")
    r = subprocess.run([URLAB, "run", bad_scene, "--duration", "1", "--no-network"],
                       capture_output=True, text=True, timeout=60)
    if r.returncode == 0 or "bad.yaml:2" not in r.stderr or "files_dir" not in r.stderr:
        fail(f"network.files_dir on a file: exit {r.returncode}: {r.stderr}")
    with open(bad_scene, "w") as f:
        f.write("""articulations:
  - {name: arm, mjcf: arm.xml}
network:
  max_queued_steps: 0.5
""")
    r = subprocess.run([URLAB, "run", bad_scene, "--duration", "1", "--no-network"],
                       capture_output=True, text=True, timeout=60)
    if r.returncode == 0 or "bad.yaml:4" not in r.stderr:
        fail(f"network.max_queued_steps 0.5: exit {r.returncode}: {r.stderr}")
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
