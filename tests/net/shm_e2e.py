#!/usr/bin/python3
"""End to end: the step server's shared-memory channel with real processes (`urlab run` on
ephemeral ports, Python clients in their own processes), killed with SIGKILL on either side.

0. The same lockstep rollout over the channel and over ZeroMQ gives the same observations.
1. A Python client on the channel drives in lockstep, then is killed: the server notices within
   its sweep (the log says so), frees the lease (another client drives without force) and no
   file of the server's is left in /dev/shm.
2. A client waits for a long step when the server is killed: it gets ShmError (the server died),
   not a timeout, and nothing is left in /dev/shm.
4. (Issue 38, case 8) A second client attaching to a channel already attached gets ShmError
   (not AttributeError), and the first client's channel stays open.
3. A server stopped with SIGINT removes the file of an offer not taken; one killed with SIGKILL
   leaves it, and the next server removes it when it starts.
First, the Python client's wait policy (urlab_client.shm.spin_budget) against the C++ one's
table (tests/net/shm_wait_test.cc).
Usage: shm_e2e.py URLAB_BINARY SOURCE_DIR
"""
import glob
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
import msgpack  # noqa: E402
import zmq  # noqa: E402
from urlab_client import StepClient  # noqa: E402
from urlab_client.shm import (ShmChannel, ShmError, available, spare_core,  # noqa: E402
                              spin_budget)
from urlab_process import arm_scene, fail, start_urlab  # noqa: E402

CLIENT = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
from urlab_client import StepClient
c = StepClient(sys.argv[2])
assert c.transport == "shm", c.transport
c.set_mode("direct")
for i in range(50):
    c.step(2)
print("ready", flush=True)
time.sleep(600)
"""


def files_of(proc):
    return glob.glob(f"/dev/shm/urlab-shm-{proc.pid}-*")


def wait_for(what, condition, proc, seconds=20):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return
        time.sleep(0.05)
    fail(what, proc)


def check_wait_policy():
    """The Python client's wait policy is the C++ one's (tests/net/shm_wait_test.cc's table):
    seconds expected -> spin with a free core, without one, whether the cores are asked."""
    table = [(0, 30e-6, 30e-6, False), (5e-6, 30e-6, 30e-6, False),
             (46e-6, 138e-6, 138e-6, False), (100e-6, 300e-6, 300e-6, False),
             (600e-6, 800e-6, 0.0, True), (1e-3, 1.3e-3, 0.0, True),
             (2.5e-3, 3e-3, 0.0, True), (3e-3, 3e-3, 0.0, True),
             (3.001e-3, 30e-6, 30e-6, False), (40e-3, 30e-6, 30e-6, False)]
    for expected, spare, busy, asks in table:
        asked = []
        got = (spin_budget(expected, lambda: asked.append(1) or True),
               spin_budget(expected, lambda: asked.append(1) or False))
        if abs(got[0] - spare) > 1e-9 or abs(got[1] - busy) > 1e-9 or bool(asked) != asks:
            fail(f"spin_budget({expected}): {got}, asked {len(asked)}; expected "
                 f"{(spare, busy)}, asked {asks}")
    if spare_core() not in (True, False):
        fail("spare_core() is not a bool")
    # Threads about to wake count as runnable: more of them than cores leave none spare.
    if spare_core(waking=(os.cpu_count() or 1)):
        fail("spare_core(waking=cores) found a spare core beside this thread")
    print("the wait policy: the same table as the C++ one")


def main():
    if not available() or not os.path.isdir("/dev/shm"):
        print("SKIP: shared memory needs Linux x86_64 and /dev/shm")
        return
    check_wait_policy()
    tmp = tempfile.mkdtemp(prefix="urlab_shm_")
    scene = arm_scene(tmp, ephemeral_ports=True)

    # 0. The same rollout over shared memory and over ZeroMQ: the same observations.
    proc, endpoints = start_urlab(URLAB, scene, "--files-dir", os.path.join(tmp, "files"))
    rpc = endpoints[3]
    runs = {}
    for shm in (True, False):
        with StepClient(rpc, shared_memory=shm) as c:
            if c.transport != ("shm" if shm else "zmq"):
                fail(f"transport {c.transport} with shared_memory={shm}", proc)
            c.set_mode("direct")
            c.reset()
            runs[shm] = [c.step(2, controls={"arm": [0.3 * (i % 7) / 7, -0.2]})["per_articulation"]
                         ["arm"]["qpos"].tolist() for i in range(200)]
    if runs[True] != runs[False]:
        fail("the rollouts over shared memory and ZeroMQ differ", proc)
    print("the same 200-request rollout over shared memory and over ZeroMQ")

    # 4. A second attach to a channel in use.
    z = zmq.Context.instance().socket(zmq.REQ)
    z.setsockopt(zmq.LINGER, 0)
    z.setsockopt(zmq.RCVTIMEO, 20000)
    z.connect(rpc)
    z.send(msgpack.packb({"op": "hello", "shm": True}))
    offer = msgpack.unpackb(z.recv())["shm"]
    first = ShmChannel(offer["path"], offer["generation"])
    try:
        ShmChannel(offer["path"], offer["generation"])
        fail("a second attach to one channel succeeded", proc)
    except ShmError as e:
        if "another client attached already" not in str(e):
            fail(f"a second attach: {e}", proc)
    except Exception as e:  # noqa: BLE001
        fail(f"a second attach raised {type(e).__name__}: {e}, not ShmError", proc)
    time.sleep(0.6)  # past the server's sweep (200 ms)
    if first.server_gone():
        fail("the refused second attach closed the first client's channel", proc)
    first.close()
    z.close()
    print("a second attach: ShmError, the first client's channel stays open")

    # 1. A killed client.
    client = subprocess.Popen([sys.executable, "-c", CLIENT, os.path.join(SOURCE, "clients",
                                                                          "python"), rpc],
                              stdout=subprocess.PIPE, text=True)
    if client.stdout.readline().strip() != "ready":
        fail("the shared-memory client did not start", proc)
    with StepClient(rpc, shared_memory=False) as observer:
        if observer.call("get_counters")["driver"] is None:
            fail("the client on shared memory does not hold the lease", proc)
        client.kill()
        client.wait()
        wait_for("the server kept the dead client's lease",
                 lambda: observer.call("get_counters")["driver"] is None, proc)
        observer.set_mode("direct")  # drives now, without force
        observer.step()
    wait_for("a file of the server's is left in /dev/shm", lambda: not files_of(proc), proc)
    proc.send_signal(signal.SIGINT)
    log = proc.communicate(timeout=30)[1]
    if "shared-memory client of session" not in log or "closed or died" not in log:
        fail("the log does not say the shared-memory client went away:\n" + log)
    print("killed client: noticed, lease freed, no files left")

    # 2. A killed server while a client waits on the channel (--duration counts the client's
    # steps too: room for the 100,000-step requests below).
    proc, endpoints = start_urlab(URLAB, scene, "--files-dir", os.path.join(tmp, "files"),
                                  duration=36000)
    c = StepClient(endpoints[3], timeout=120.0)
    if c.transport != "shm":
        fail(f"transport {c.transport}", proc)
    c.set_mode("direct")
    threading.Timer(0.5, lambda: proc.send_signal(signal.SIGKILL)).start()
    t0 = time.monotonic()
    try:
        while time.monotonic() - t0 < 60:
            c.step(n_steps=100000)
        fail("the client never noticed the server's death")
    except ShmError as e:
        print(f"killed server: the client got '{e}' after {time.monotonic() - t0:.2f} s "
              "(timeout 120 s)")
    except TimeoutError as e:
        fail(f"a timeout instead of the server's death: {e}")
    proc.wait()
    c.close()
    if files_of(proc):
        fail(f"files left: {files_of(proc)}")

    # 3. An offer never taken: removed by SIGINT; left by SIGKILL and reclaimed by the next server.
    proc, endpoints = start_urlab(URLAB, scene, "--files-dir", os.path.join(tmp, "files"))
    # A signal ends the process at once until the run plays (its sockets are bound and serving a
    # little earlier): offers made in that window are left for the next server to reclaim, as
    # after SIGKILL. Wait for the run to play (under ThreadSanitizer the window is long).
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            fail("urlab exited before playing", proc)
        if "playing " in line:
            break
    time.sleep(0.2)
    ctx = zmq.Context.instance()
    s = ctx.socket(zmq.REQ)
    s.setsockopt(zmq.LINGER, 0)
    s.setsockopt(zmq.RCVTIMEO, 10000)
    s.connect(endpoints[3])
    s.send(msgpack.packb({"op": "hello", "shm": True}))
    offer = msgpack.unpackb(s.recv(), raw=False).get("shm")
    s.close(0)
    if not offer or not os.path.exists(offer["path"]):
        fail(f"no offer file: {offer}", proc)
    # A server stopped with SIGINT withdraws its offers: the file goes with it.
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=30)
    if os.path.exists(offer["path"]):
        fail(f"SIGINT left {offer['path']}")
    proc, endpoints = start_urlab(URLAB, scene, "--files-dir", os.path.join(tmp, "files"))
    s = ctx.socket(zmq.REQ)
    s.setsockopt(zmq.LINGER, 0)
    s.setsockopt(zmq.RCVTIMEO, 10000)
    s.connect(endpoints[3])
    s.send(msgpack.packb({"op": "hello", "shm": True}))
    offer = msgpack.unpackb(s.recv(), raw=False).get("shm")
    s.close(0)
    proc.kill()
    proc.wait()
    if not offer or not os.path.exists(offer["path"]):
        fail("the killed server's file is gone already (nothing to reclaim)")
    proc2, _ = start_urlab(URLAB, scene, "--files-dir", os.path.join(tmp, "files"))
    try:
        if os.path.exists(offer["path"]):
            fail(f"the stale file {offer['path']} was not reclaimed", proc2)
    finally:
        proc2.send_signal(signal.SIGINT)
        proc2.communicate(timeout=30)
    print("stale file of a killed server reclaimed by the next one")
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
