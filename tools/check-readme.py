#!/usr/bin/env python3
"""Runs README.md's quick start word for word: every line of the shell blocks directly under
"## Quick start", then every Python snippet of README.md and docs/*.md, each saved as a script
(so that Dask's worker processes can import it) and run against the scene its text names
("`./build/urlab run SCENE`" in the prose since the previous fenced block, started in the
background until the snippet ends), or by itself when the text names none. Each runs from the
repository root with bash or this script's own Python (ctest: ${URLAB_PYTHON}, the project's
.venv, where the quick start installs urlab_client); any non-zero exit (or a line running longer
than --timeout seconds) fails the check, naming the line.

    .venv/bin/python tools/check-readme.py [--root DIR] [--build DIR] [--timeout S] [--list]
                                           [--snippets]

ctest runs it as `readme.quick_start` (label readme). The README's lines name ./build, so the
check only means something against the build in ROOT/build: given another --build it skips
(exit 77, ctest's skip code). --snippets runs the Python snippets alone.
"""
import argparse
import fcntl
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time

SKIP = 77


def section(text, title):
    """The text of the level-2 section `title` (up to the next level-2 heading)."""
    m = re.search(r"^## " + re.escape(title) + r"\s*$", text, re.M)
    if not m:
        raise SystemExit(f"README.md has no '## {title}' section")
    rest = text[m.end():]
    end = re.search(r"^## ", rest, re.M)
    return rest[:end.start()] if end else rest


def blocks(text, language):
    """(offset, body) of every fenced block of `language`."""
    pattern = re.compile(r"^```" + language + r"\s*\n(.*?)^```\s*$", re.M | re.S)
    return [(m.start(), m.group(1)) for m in pattern.finditer(text)]


def shell_lines(text):
    """The lines of the shell blocks directly under "## Quick start" (before its subsections)."""
    quick = section(text, "Quick start")
    sub = re.search(r"^### ", quick, re.M)
    out = []
    for _, body in blocks(quick[:sub.start()] if sub else quick, "sh"):
        for line in body.splitlines():
            if line.strip() and not line.lstrip().startswith("#"):
                out.append(line)
    return out


def python_snippets(text, name="README.md"):
    """(document, server command or None, snippet) for every Python block: the last
    `./build/urlab run ...` in backticks in the prose since the previous fenced block."""
    out = []
    for start, body in blocks(text, "python"):
        before = text[:start]
        fence = before.rfind("```\n", 0, len(before) - 1)
        prose = before[fence + 4:] if fence >= 0 else before
        servers = re.findall(r"`(\./build/urlab run [^`]+)`", prose)
        out.append((name, servers[-1] if servers else None, body))
    return out


def documents(root):
    """README.md, then docs/*.md: (name, text)."""
    names = ["README.md"] + sorted(os.path.join("docs", n)
                                   for n in os.listdir(os.path.join(root, "docs"))
                                   if n.endswith(".md"))
    out = []
    for name in names:
        with open(os.path.join(root, name), encoding="utf-8") as f:
            out.append((name, f.read()))
    return out


def run_line(line, root, timeout):
    print(f"$ {line}", flush=True)
    start = time.monotonic()
    try:
        r = subprocess.run(["bash", "-c", line], cwd=root, timeout=timeout,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    except subprocess.TimeoutExpired as e:
        tail = (e.stdout or b"")[-2000:]
        print(tail if isinstance(tail, str) else tail.decode(errors="replace"))
        return f"ran longer than {timeout} s: {line}"
    print("\n".join(r.stdout.splitlines()[-6:]))
    print(f"  (exit {r.returncode}, {time.monotonic() - start:.1f} s)", flush=True)
    if r.returncode != 0:
        print(r.stdout[-4000:])
        return f"exit {r.returncode}: {line}"
    return None


def wait_for_port(port, proc, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if proc.poll() is not None:
            return False
        with socket.socket() as s:
            s.settimeout(0.5)
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.2)
    return False


def run_snippet(document, server, snippet, root, timeout):
    where = f"{document}, " + (f"server {server}" if server else "no server")
    proc = None
    if server:
        print(f"$ {server} &", flush=True)
        proc = subprocess.Popen(["bash", "-c", "exec " + server], cwd=root,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        if proc and not wait_for_port(5559, proc, 120):  # the step server: the scene is playing
            out = proc.communicate(timeout=10)[0] if proc.poll() is not None else ""
            return f"the server did not start: {server}\n{out[-3000:]}"
        with tempfile.TemporaryDirectory(prefix="urlab_snippet_") as folder:
            script = os.path.join(folder, "snippet.py")
            with open(script, "w", encoding="utf-8") as f:
                f.write(snippet)
            print(f"$ cat > snippet.py <<'EOF'\n{snippet}EOF\n$ {sys.executable} snippet.py",
                  flush=True)
            try:
                r = subprocess.run([sys.executable, script], cwd=root, timeout=timeout,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            except subprocess.TimeoutExpired:
                return f"a Python snippet ran longer than {timeout} s ({where})"
        print(r.stdout[-3000:], flush=True)
        if r.returncode != 0:
            return f"a Python snippet exited {r.returncode} ({where})"
        return None
    finally:
        if proc is not None and proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=os.path.dirname(here), help="the repository root")
    ap.add_argument("--build", help="the build folder ctest runs from (skip unless ROOT/build)")
    ap.add_argument("--timeout", type=float, default=600, help="seconds per line or snippet")
    ap.add_argument("--list", action="store_true", help="print what would run, run nothing")
    ap.add_argument("--snippets", action="store_true", help="the Python snippets only")
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    docs = documents(root)
    lines = [] if args.snippets else shell_lines(docs[0][1])
    snippets = [s for name, text in docs for s in python_snippets(text, name)]
    if args.list:
        for line in lines:
            print(line)
        for document, server, snippet in snippets:
            print(f"# {document}\n" + (f"{server} &\n" if server else "") +
                  f"{sys.executable} <<'EOF'\n{snippet}EOF")
        return 0
    if args.build and os.path.realpath(args.build) != os.path.realpath(os.path.join(root, "build")):
        print(f"skipped: the README's lines use ./build, this build is {args.build}")
        return SKIP
    if (not lines and not args.snippets) or not snippets:
        print("README.md: no quick-start lines or no Python snippets found")
        return 1
    # The README plays scenes on the default ports, which only one run can hold: a second check on
    # this machine (another clone's ctest) waits here for the first to finish.
    lock = open(os.path.join(tempfile.gettempdir(), "urlab-readme-default-ports.lock"), "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        print("another README check holds the default ports: waiting for it", flush=True)
        fcntl.flock(lock, fcntl.LOCK_EX)
    failures = []
    for line in lines:
        problem = run_line(line, root, args.timeout)
        if problem:
            failures.append(problem)
    for document, server, snippet in snippets:
        problem = run_snippet(document, server, snippet, root, args.timeout)
        if problem:
            failures.append(problem)
    print(f"{len(lines)} quick-start lines and {len(snippets)} Python snippets: "
          f"{len(failures)} failed")
    for problem in failures:
        print("FAILED: " + problem)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
