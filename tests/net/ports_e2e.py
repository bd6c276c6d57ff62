#!/usr/bin/python3
"""End to end: ports chosen by the system, the announce file, the handshake's identity, and a
taken port stopping a headless run before it simulates.

1. `urlab run SCENE --ports auto --announce A` (a scene with no network section, whose defaults
   are 5555..5559): the announce file appears once bound and names the run's pid, scene,
   instance, session and endpoints, none of them a default port; a client that requires that
   identity is served, one that requires another is refused (wrong_server); the file is removed
   when the run ends.
2. A second run whose step server port is the first run's: exit 1, before any step, naming the
   port and the first run's pid and command line; with --allow-no-network it plays without it.
3. `--port-base N`: the five sockets on N..N+4.
Usage: ports_e2e.py URLAB_BINARY SOURCE_DIR
"""
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import time

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SOURCE, "clients", "python"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "support"))
from urlab_client import StepClient, UrlabError  # noqa: E402
from urlab_process import arm_scene  # noqa: E402

DEFAULT_PORTS = {5555, 5556, 5557, 5558, 5559}


def fail(message, *procs):
    for p in procs:
        if p and p.poll() is None:
            p.kill()
    print("FAIL:", message)
    sys.exit(1)


def wait_for_file(path, proc, timeout=60):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if os.path.exists(path):
            with open(path) as f:
                return json.load(f)  # written whole (renamed into place): never partial
        if proc.poll() is not None:
            fail(f"urlab exited ({proc.returncode}) before announcing:\n{proc.stderr.read()}")
        time.sleep(0.05)
    fail(f"no announce file {path} after {timeout} s", proc)


def port_of(endpoint):
    return int(endpoint.rsplit(":", 1)[1])


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_ports_")
    scene = arm_scene(tmp, "ports_arm.yaml")
    announce = os.path.join(tmp, "a.json")
    first = subprocess.Popen([URLAB, "run", scene, "--ports", "auto", "--announce", announce,
                              "--instance", "first", "--duration", "60", "--no-cameras"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        a = wait_for_file(announce, first)
        if a["pid"] != first.pid or a["scene"] != "ports_arm" or a["instance"] != "first":
            fail(f"announce file: {a}", first)
        if not re.fullmatch(r"[0-9a-f]{16}", a["session"]):
            fail(f"session id {a['session']!r}", first)
        ports = {k: port_of(e) for k, e in a["endpoints"].items()}
        if set(ports.values()) & DEFAULT_PORTS or len(set(ports.values())) != 4:
            fail(f"--ports auto bound {ports}", first)
        if a["transports"] != [{"kind": "zmq", "endpoint": a["endpoints"]["rpc"]}]:
            fail(f"transports {a['transports']}", first)
        rpc = a["endpoints"]["rpc"]
        ident = {"scene": a["scene"], "instance": a["instance"], "server_session": a["session"]}
        with StepClient(rpc, require=ident) as c:
            if {k: c.info[k] for k in ident} != ident:
                fail(f"hello_ok identity {[c.info.get(k) for k in ident]}", first)
        for wrong in ({"instance": "second"}, {"server_session": "0" * 16}, {"scene": "x"}):
            try:
                StepClient(rpc, require=wrong).close()
                fail(f"require {wrong} was served", first)
            except UrlabError as e:
                if e.code != "wrong_server":
                    fail(f"require {wrong}: {e}", first)
        print(f"announced {a['endpoints']} session {a['session']}; identity required and checked")

        # 2. The step server's port is taken by the first run.
        taken = os.path.join(tmp, "taken.yaml")
        with open(taken, "w") as f:
            f.write(open(scene).read() + f"""network:
  state: "tcp://127.0.0.1:*"
  control: "tcp://127.0.0.1:*"
  info: "tcp://127.0.0.1:*"
  rpc: "{rpc}"
""")
        second = subprocess.run([URLAB, "run", taken, "--duration", "30", "--no-cameras"],
                                capture_output=True, text=True, timeout=60)
        want = f"port {ports['rpc']} (step server) is in use by pid {first.pid} (urlab run "
        if second.returncode != 1 or want not in second.stderr:
            fail(f"a taken port: exit {second.returncode}, stderr:\n{second.stderr}", first)
        if "summary:" in second.stdout or "playing " in second.stderr:
            fail(f"the run simulated before failing:\n{second.stdout}{second.stderr}", first)
        print("taken port:", second.stderr.strip().splitlines()[-1])
        allowed = subprocess.run([URLAB, "run", taken, "--duration", "0.5", "--no-cameras",
                                  "--allow-no-network"], capture_output=True, text=True,
                                 timeout=60)
        if allowed.returncode != 0 or "summary:" not in allowed.stdout or \
                want not in allowed.stderr:
            fail(f"--allow-no-network: exit {allowed.returncode}:\n{allowed.stderr}", first)
    finally:
        if first.poll() is None:
            first.terminate()
            first.wait(timeout=30)
    if os.path.exists(announce):
        fail("the announce file outlived the run")

    # 3. --port-base: five ports the system just called free (another program may take one in
    # between: then try another base).
    for attempt in range(5):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        base = s.getsockname()[1]
        s.close()
        if base + 4 > 65535:
            continue
        ann = os.path.join(tmp, f"base{attempt}.json")
        run = subprocess.Popen([URLAB, "run", scene, "--port-base", str(base), "--announce", ann,
                                "--duration", "60", "--no-cameras"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while not os.path.exists(ann) and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        if run.poll() is not None:
            err = run.stderr.read()
            if "is in use by" in err:
                continue
            fail(f"--port-base {base}: exit {run.returncode}:\n{err}")
        with open(ann) as f:
            got = json.load(f)["endpoints"]
        run.terminate()
        run.wait(timeout=30)
        want = {"state": base, "control": base + 1, "info": base + 2, "rpc": base + 4}
        if {k: port_of(e) for k, e in got.items()} != want:
            fail(f"--port-base {base}: {got}")
        print(f"--port-base {base}: {got}")
        break
    else:
        fail("no free run of five ports in five tries")
    print("PASS")


if __name__ == "__main__":
    main()
