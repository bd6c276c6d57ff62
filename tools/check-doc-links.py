#!/usr/bin/env python3
"""Checks that every Markdown document the repository names exists in the repository: each
Markdown file name (such as docs/network.md) written in a tracked source, script, test or
document resolves from the repository root or from the naming file's folder. A fresh clone has nothing else, so a
reference to a document outside the repository (or to one renamed) fails, naming file and line.

    /usr/bin/python3 tools/check-doc-links.py [--root DIR]

ctest runs it as `docs.links`.
"""
import argparse
import os
import re
import subprocess
import sys

# A document name: letters, digits, _ . - and / before ".md", not part of a longer word or URL.
REFERENCE = re.compile(r"(?<![\w./:-])((?:[\w.-]+/)*[\w.-]+\.md)\b")
SKIPPED_FOLDERS = ("tests/data/",)  # third-party models and their own texts
TEXT_SUFFIXES = (".md", ".cc", ".h", ".py", ".sh", ".txt", ".cmake", ".yaml", ".yml", ".in")


def tracked_files(root):
    try:
        out = subprocess.run(["git", "-C", root, "ls-files"], check=True, capture_output=True,
                             text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        print("check-doc-links: not a git checkout; skipped")
        sys.exit(77)
    for path in out.splitlines():
        if path.startswith(SKIPPED_FOLDERS):
            continue
        if path.endswith(TEXT_SUFFIXES) or os.path.basename(path) in ("run", "CMakeLists.txt"):
            yield path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    missing = []
    checked = 0
    for path in tracked_files(root):
        try:
            with open(os.path.join(root, path), encoding="utf-8") as f:
                lines = f.read().splitlines()
        except (UnicodeDecodeError, FileNotFoundError):
            continue
        folder = os.path.dirname(path)
        for number, line in enumerate(lines, 1):
            for name in REFERENCE.findall(line):
                checked += 1
                candidates = [os.path.join(root, name), os.path.join(root, folder, name)]
                if not any(os.path.isfile(c) for c in candidates):
                    missing.append(f"{path}:{number}: '{name}' is not in the repository")
    for m in missing:
        print(m)
    print(f"check-doc-links: {checked} references, {len(missing)} missing")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
