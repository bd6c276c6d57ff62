#!/usr/bin/python3
"""Issue 38, case 6: `urlab sweep` on bad input. Every bad sweep file is an error naming the
file, the line and the field, like a scene file's (exit 1, no Python traceback), found before a
cluster starts, so none hangs: YAML syntax errors, a binary file, a FIFO as the sweep file, deep
nesting, `output: /dev/null`, `workers: many`, 0, -3 or 100000, `duration: .inf` or '2',
`seeds: [true]`, `timeout: -5`, `articulation: 5`, two policies of one name (two rows, one
recording), a scene given twice.
Usage: sweep_bad_input_e2e.py URLAB_BINARY SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

URLAB, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
failures = []


def sweep(path, *extra):
    try:
        return subprocess.run([URLAB, "sweep", path, *extra], capture_output=True, text=True,
                              timeout=30)
    except subprocess.TimeoutExpired:
        return None


def main():
    tmp = tempfile.mkdtemp(prefix="urlab_sweep_bad_")
    os.environ["DASK_TEMPORARY_DIRECTORY"] = os.path.join(tmp, "dask")
    scene = os.path.join(SOURCE, "examples", "models", "servo_arm.xml")
    good = (f"scenes: [{scene}]\nseeds: [0]\nduration: 0.5\narticulation: servo_arm\n"
            "policies:\n  - {name: still, command: 'true'}\n")

    def case(label, text, needles, *extra, binary=False):
        path = os.path.join(tmp, label + ".yaml")
        with open(path, "wb" if binary else "w") as f:
            f.write(text)
        check(label, path, needles, *extra)

    def check(label, path, needles, *extra):
        r = sweep(path, *extra)
        if r is None:
            failures.append(f"{label}: still running after 30 s")
            return
        message = r.stderr.strip()
        if r.returncode != 1 or "Traceback" in message:
            failures.append(f"{label}: exit {r.returncode}:\n{message[-2000:]}")
            return
        missing = [n for n in ([] if extra else [path]) + needles if n not in message]
        if missing:
            failures.append(f"{label}: expected {missing} in:\n{message}")
        else:
            print(f"{label}: {message.splitlines()[-1]}")

    case("syntax", good + "output: a: b\n", [":7:", "YAML"])
    case("unclosed", good + "policies: [\n", [":8:", "YAML"])
    case("tab", good + "\tseeds: [1]\n", [":7:"])
    case("binary", b"\x00\xff\xfe\x89PNG\r\n\x1a\n" + bytes(range(256)), ["not a text"],
         binary=True)
    case("nested", "scenes: " + "[" * 5000 + "]" * 5000 + "\n", ["nested"])
    case("null_output", good + "output: /dev/null\n", [":7:", "output", "not a folder"])
    case("workers_many", good + "cluster: {workers: many}\n", [":7:", "cluster.workers"])
    for n in (0, -3, 100000):
        case(f"workers_{n}", good + f"cluster: {{workers: {n}}}\n", [":7:", "cluster.workers",
                                                                       "[1, 64]"])
    case("workers_flag", good, ["--workers", "[1, 64]"], "--workers", "0")
    case("duration_inf", good.replace("duration: 0.5", "duration: .inf"),
         [":3:", "duration", "(0, 86400]"])
    case("duration_text", good.replace("duration: 0.5", "duration: '2'"),
         [":3:", "duration", "a number"])
    case("seeds_bool", good.replace("seeds: [0]", "seeds: [true]"), [":2:", "seeds[0]"])
    case("seeds_big", good.replace("seeds: [0]", "seeds: [9007199254740992]"),
         [":2:", "seeds[0]", "9007199254740991"])
    case("seeds_twice", good.replace("seeds: [0]", "seeds: [1, 1]"), [":2:", "seeds", "twice"])
    case("timeout", good + "timeout: -5\n", [":7:", "timeout"])
    case("articulation", good.replace("articulation: servo_arm", "articulation: 5"),
         [":4:", "articulation"])
    case("same_policy", good + "  - {name: still, command: 'false'}\n",
         [":7:", "policies[1].name", "still"])
    case("same_scene", good.replace(f"scenes: [{scene}]", f"scenes: [{scene}, {scene}]"),
         [":1:", "scenes[1]"])
    case("scene_number", good.replace(f"scenes: [{scene}]", "scenes: [5]"), [":1:", "scenes[0]"])
    case("top_list", "- 1\n- 2\n", [":1:", "a mapping"])
    case("unknown", good + "workers: 3\n", [":7:", "unknown key 'workers'"])
    fifo = os.path.join(tmp, "fifo.yaml")
    os.mkfifo(fifo)
    check("fifo", fifo, ["not a regular file"])

    if failures:
        for f in failures:
            print("FAIL:", f)
        sys.exit(1)
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
