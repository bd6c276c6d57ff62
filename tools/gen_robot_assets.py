#!/usr/bin/env python3
"""Writes the small asset files of the robot-style corpus (tests/data/mjcf/robots).

The models there are written the way public robot packages (Unitree's H1/Go2/G1, MuJoCo
Menagerie) are: assets named only by their file. This script writes those files: low-poly
closed meshes as binary STL and OBJ, PNG textures, a PNG height field and an SKN skin. Standard
library only, deterministic; the output is committed so tests never run this script.

    python3 tools/gen_robot_assets.py [--out tests/data/mjcf/robots]
"""
import argparse
import math
import os
import struct
import zlib

# ---- meshes (closed, outward-facing triangles) ----


def box(sx, sy, sz, center=(0.0, 0.0, 0.0)):
    """Axis-aligned box with half-sizes sx, sy, sz."""
    cx, cy, cz = center
    v = [(cx + x * sx, cy + y * sy, cz + z * sz)
         for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    # Index = 4*(x>0) + 2*(y>0) + (z>0); faces counter-clockwise seen from outside.
    quads = [(0, 1, 3, 2), (4, 6, 7, 5),  # -x, +x
             (0, 4, 5, 1), (2, 3, 7, 6),  # -y, +y
             (0, 2, 6, 4), (1, 5, 7, 3)]  # -z, +z
    f = []
    for a, b, c, d in quads:
        f += [(a, b, c), (a, c, d)]
    return v, f


def cylinder(r, half, n=12, axis="z", center=(0.0, 0.0, 0.0)):
    """Closed n-sided prism of radius r and half-length `half` along `axis`."""
    ring = [(r * math.cos(2 * math.pi * i / n), r * math.sin(2 * math.pi * i / n)) for i in range(n)]
    v = [(x, y, -half) for x, y in ring] + [(x, y, half) for x, y in ring]
    v += [(0.0, 0.0, -half), (0.0, 0.0, half)]
    bottom, top = 2 * n, 2 * n + 1
    f = []
    for i in range(n):
        j = (i + 1) % n
        f += [(i, j, n + j), (i, n + j, n + i)]  # side
        f += [(bottom, j, i), (top, n + i, n + j)]  # caps
    # Cyclic permutations of the coordinates are rotations: faces stay outward.
    rotate = {"z": lambda p: p, "x": lambda p: (p[2], p[0], p[1]),
              "y": lambda p: (p[1], p[2], p[0])}[axis]
    v = [rotate(p) for p in v]
    v = [(a + center[0], b + center[1], c + center[2]) for a, b, c in v]
    return v, f


def merge(*parts):
    v, f = [], []
    for pv, pf in parts:
        base = len(v)
        v += pv
        f += [(a + base, b + base, c + base) for a, b, c in pf]
    return v, f


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    w = [c[i] - a[i] for i in range(3)]
    n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return [x / length for x in n]


def stl(mesh):
    v, f = mesh
    data = b"urlab robot corpus".ljust(80, b"\0") + struct.pack("<I", len(f))
    for a, b, c in f:
        data += struct.pack("<3f", *normal(v[a], v[b], v[c]))
        for p in (v[a], v[b], v[c]):
            data += struct.pack("<3f", *p)
        data += struct.pack("<H", 0)
    return data


def obj(mesh):
    v, f = mesh
    lines = ["# urlab robot corpus"]
    lines += ["v %.6f %.6f %.6f" % p for p in v]
    lines += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in f]
    return ("\n".join(lines) + "\n").encode()


# ---- images ----


def png(width, height, rows, gray=False):
    raw = b"".join(b"\0" + bytes(r) for r in rows)

    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body +
                struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

    color = 0 if gray else 2
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, color, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checker(n, cell, c1, c2):
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            row += c1 if ((x // cell) + (y // cell)) % 2 == 0 else c2
        rows.append(row)
    return png(n, n, rows)


def terrain(n):
    rows = []
    for y in range(n):
        rows.append([int(127 + 60 * math.sin(x * 0.7) * math.cos(y * 0.5)) for x in range(n)])
    return png(n, n, rows, gray=True)


# ---- skin ----


def skn(vertices, faces, bones):
    """bones: (body, bindpos, bindquat, vertex ids, weights)."""
    data = struct.pack("<4i", len(vertices), 0, len(faces), len(bones))
    for p in vertices:
        data += struct.pack("<3f", *p)
    for t in faces:
        data += struct.pack("<3i", *t)
    for body, pos, quat, ids, weights in bones:
        data += body.encode().ljust(40, b"\0")
        data += struct.pack("<3f", *pos) + struct.pack("<4f", *quat)
        data += struct.pack("<i", len(ids)) + struct.pack("<%di" % len(ids), *ids)
        data += struct.pack("<%df" % len(ids), *weights)
    return data


# ---- the corpus ----


def files():
    out = {}
    # Go2-style quadruped: OBJ meshes under meshdir, a PNG texture under texturedir.
    out["go2/assets/meshes/base.obj"] = obj(merge(box(0.19, 0.047, 0.057),
                                                  cylinder(0.05, 0.045, axis="y",
                                                           center=(0.285, 0, 0.01))))
    out["go2/assets/meshes/hip.obj"] = obj(cylinder(0.046, 0.02, axis="y"))
    out["go2/assets/meshes/thigh.obj"] = obj(box(0.017, 0.012, 0.1065, center=(0, 0, -0.1065)))
    out["go2/assets/meshes/calf.obj"] = obj(cylinder(0.012, 0.1, center=(0.004, 0, -0.1)))
    out["go2/assets/meshes/foot.obj"] = obj(box(0.02, 0.02, 0.02))
    out["go2/assets/textures/ground.png"] = checker(16, 4, (60, 80, 100), (90, 110, 130))
    out["go2/assets/textures/go2_body.png"] = checker(8, 2, (200, 200, 200), (40, 40, 40))
    # H1-style humanoid: STL meshes (Unitree's upper-case .STL) under assetdir, a height field.
    h1 = {
        "pelvis": box(0.06, 0.11, 0.06),
        "hip_yaw_link": cylinder(0.04, 0.05),
        "hip_roll_link": cylinder(0.045, 0.04, axis="x"),
        "hip_pitch_link": box(0.04, 0.04, 0.2, center=(0, 0, -0.2)),
        "knee_link": box(0.035, 0.035, 0.2, center=(0, 0, -0.2)),
        "ankle_link": box(0.1, 0.035, 0.02, center=(0.04, 0, -0.04)),
        "torso_link": box(0.08, 0.14, 0.2, center=(0, 0, 0.22)),
        "shoulder_pitch_link": cylinder(0.04, 0.04, axis="y"),
        "shoulder_roll_link": cylinder(0.04, 0.04, axis="x"),
        "shoulder_yaw_link": box(0.03, 0.03, 0.1, center=(0, 0, -0.1)),
        "elbow_link": box(0.12, 0.03, 0.03, center=(0.12, 0, 0)),
        "logo_link": box(0.01, 0.05, 0.05),
    }
    for name, mesh in h1.items():
        out["h1/assets/%s.STL" % name] = stl(mesh)
    out["h1/assets/rough.png"] = terrain(32)
    # Menagerie-style arm: STL and OBJ under meshdir, an SKN cover skin on two links.
    out["arm/assets/base.stl"] = stl(cylinder(0.08, 0.05, center=(0, 0, 0.05)))
    out["arm/assets/link1.stl"] = stl(cylinder(0.05, 0.15, center=(0, 0, 0.15)))
    out["arm/assets/link2.obj"] = obj(box(0.04, 0.04, 0.15, center=(0, 0, 0.15)))
    out["arm/assets/link3.obj"] = obj(box(0.035, 0.035, 0.12, center=(0, 0, 0.12)))
    out["arm/assets/finger.stl"] = stl(box(0.01, 0.008, 0.03, center=(0, 0, 0.03)))
    # Cover skin: a box around link2 (bone link2 at z=0.40 in the reference pose) and link3
    # (z=0.70), split at z=0.70.
    sv = [(x, y, z) for z in (0.40, 0.70, 0.94) for x in (-0.05, 0.05) for y in (-0.05, 0.05)]
    sf = []
    for lo in (0, 4):
        hi = lo + 4
        # ring quads between layer lo and hi: vertices (x-,y-)0 (x-,y+)1 (x+,y-)2 (x+,y+)3
        for a, b in ((0, 2), (2, 3), (3, 1), (1, 0)):
            sf += [(lo + a, lo + b, hi + b), (lo + a, hi + b, hi + a)]
    sf += [(0, 1, 3), (0, 3, 2), (8, 10, 11), (8, 11, 9)]
    out["arm/assets/cover.skn"] = skn(sv, sf, [
        ("link2", (0, 0, 0.40), (1, 0, 0, 0), list(range(0, 8)), [1.0] * 8),
        ("link3", (0, 0, 0.70), (1, 0, 0, 0), list(range(4, 12)), [1.0] * 8),
    ])
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(here, "..", "tests", "data", "mjcf", "robots"))
    args = ap.parse_args()
    for rel, data in sorted(files().items()):
        path = os.path.join(args.out, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
        print("%6d  %s" % (len(data), rel))


if __name__ == "__main__":
    main()
