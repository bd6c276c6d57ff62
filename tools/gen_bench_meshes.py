#!/usr/bin/env python3
"""Writes the convex-decomposition benchmark meshes (closed triangle meshes of different kinds)
into a folder: mug-like (a 25k-triangle lathe with a handle), chair, table, torus, bunny-like
scan, L-bracket, terrain patch, bowl, U-channel, star prism, hook and dumbbell. Deterministic
(fixed seeds). Formats: OBJ, plus binary STL and ASCII PLY for two of them (assimp's path).

Usage: /usr/bin/python3 tools/gen_bench_meshes.py OUT_DIR [--small]
  --small: coarser meshes (a few hundred triangles each) for the CI smoke run.
"""
import math
import os
import struct
import sys

import numpy as np


class Mesh:
    def __init__(self):
        self.v = []
        self.f = []

    def add(self, other):
        base = len(self.v)
        self.v.extend(other.v)
        self.f.extend([(a + base, b + base, c + base) for a, b, c in other.f])
        return self


def grid_surface(nu, nv, point, wrap_u, wrap_v):
    """Quads of a parametric surface point(i, j) as triangles; wraps join the ends."""
    m = Mesh()
    cu = nu if wrap_u else nu + 1
    cv = nv if wrap_v else nv + 1
    for i in range(cu):
        for j in range(cv):
            m.v.append(point(i, j))
    for i in range(nu):
        for j in range(nv):
            a = i * cv + j
            b = ((i + 1) % cu) * cv + j
            c = ((i + 1) % cu) * cv + (j + 1) % cv
            d = i * cv + (j + 1) % cv
            m.f.append((a, b, c))
            m.f.append((a, c, d))
    return m


def lathe(profile, segments):
    """Surface of revolution about z of a closed profile [(r, z)...] (counter-clockwise in the
    r-z plane seen with r to the right: outward normals). Points with r == 0 are poles."""
    m = Mesh()
    n = len(profile)
    index = {}
    for k, (r, z) in enumerate(profile):
        if r == 0:
            index[(k, 0)] = len(m.v)
            m.v.append((0.0, 0.0, z))
        else:
            for s in range(segments):
                t = 2 * math.pi * s / segments
                index[(k, s)] = len(m.v)
                m.v.append((r * math.cos(t), r * math.sin(t), z))

    def vid(k, s):
        return index[(k, 0)] if profile[k][0] == 0 else index[(k, s % segments)]

    for k in range(n):
        k2 = (k + 1) % n
        for s in range(segments):
            a, b = vid(k, s), vid(k2, s)
            c, d = vid(k2, s + 1), vid(k, s + 1)
            for tri in ((a, b, c), (a, c, d)):
                if len(set(tri)) == 3:
                    m.f.append(tri)
    return m


def box(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    m = Mesh()
    m.v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
           (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    m.f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
           (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return m


def extrude(poly, z0, z1):
    """A prism over a polygon that is star-shaped from its first vertex (fan triangulation)."""
    m = Mesh()
    n = len(poly)
    for x, y in poly:
        m.v.append((x, y, z0))
    for x, y in poly:
        m.v.append((x, y, z1))
    for k in range(1, n - 1):
        m.f.append((0, k + 1, k))
        m.f.append((n, n + k, n + k + 1))
    for k in range(n):
        k2 = (k + 1) % n
        m.f.append((k, k2, n + k2))
        m.f.append((k, n + k2, n + k))
    return m


def torus(R, r, nu, nv, arc=2 * math.pi, centre=(0, 0, 0), caps=False):
    full = arc >= 2 * math.pi - 1e-9
    steps = nu

    def pt(i, j):
        u = arc * i / steps
        v = 2 * math.pi * j / nv
        return (centre[0] + (R + r * math.cos(v)) * math.cos(u),
                centre[1] + (R + r * math.cos(v)) * math.sin(u),
                centre[2] + r * math.sin(v))

    m = grid_surface(nu, nv, pt, full, True)
    if not full and caps:
        for end, flip in ((0, True), (nu, False)):
            c = len(m.v)
            u = arc * end / steps
            m.v.append((centre[0] + R * math.cos(u), centre[1] + R * math.sin(u), centre[2]))
            for j in range(nv):
                a = end * nv + j
                b = end * nv + (j + 1) % nv
                m.f.append((c, a, b) if flip else (c, b, a))
    return m


def sphere(centre, radius, n, bumps=None):
    def pt(i, j):
        th = math.pi * i / n
        ph = 2 * math.pi * j / (2 * n)
        d = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
        r = radius * (bumps(d) if bumps else 1.0)
        return tuple(np.array(centre) + r * d)

    m = Mesh()
    m.v.append(tuple(np.array(centre) + np.array([0, 0, radius * (bumps(np.array([0, 0, 1.0])) if bumps else 1)])))
    rows = []
    for i in range(1, n):
        rows.append(len(m.v))
        for j in range(2 * n):
            m.v.append(pt(i, j))
    m.v.append(tuple(np.array(centre) - np.array([0, 0, radius * (bumps(np.array([0, 0, -1.0])) if bumps else 1)])))
    south = len(m.v) - 1
    w = 2 * n
    for j in range(w):
        m.f.append((0, rows[0] + j, rows[0] + (j + 1) % w))
    for i in range(len(rows) - 1):
        for j in range(w):
            a, b = rows[i] + j, rows[i + 1] + j
            c, d = rows[i + 1] + (j + 1) % w, rows[i] + (j + 1) % w
            m.f.append((a, b, c))
            m.f.append((a, c, d))
    for j in range(w):
        m.f.append((south, rows[-1] + (j + 1) % w, rows[-1] + j))
    return m


def scale(m, s, offset=(0, 0, 0)):
    m.v = [tuple(np.array(v) * s + np.array(offset)) for v in m.v]
    return m


def mug(segments, rings):
    # Outer wall up, rim, inner wall down, inner floor, then the outer bottom.
    R, r, H, t = 0.04, 0.035, 0.1, 0.008
    prof = [(0, 0.0)]
    prof += [(R * (k / 4), 0.0) for k in range(1, 4)]
    prof += [(R, H * k / rings) for k in range(rings + 1)]
    prof += [(r, H - H * k / rings * (1 - t / H)) for k in range(rings + 1)]
    prof += [(r * (1 - k / 4), t) for k in range(1, 4)]
    prof += [(0, t)]
    # The profile above is traversed outward; make it counter-clockwise (outward normals).
    m = lathe(list(reversed(prof)), segments)
    handle = torus(0.025, 0.006, segments // 2, 12, arc=math.pi, centre=(0, 0, 0), caps=True)
    # Stand the half-torus up in the x-z plane beside the mug.
    handle.v = [(R - 0.004 + y, z, H / 2 + x) for (x, y, z) in handle.v]
    handle.f = [(a, c, b) for a, b, c in handle.f]
    return m.add(handle)


def chair():
    m = Mesh()
    m.add(box((0, 0, 0.45), (0.45, 0.45, 0.5)))
    for x, y in ((0, 0), (0.4, 0), (0, 0.4), (0.4, 0.4)):
        m.add(box((x, y, 0), (x + 0.05, y + 0.05, 0.45)))
    m.add(box((0, 0.4, 0.5), (0.45, 0.45, 0.95)))
    return m


def table():
    m = Mesh()
    m.add(box((0, 0, 0.7), (1.2, 0.8, 0.75)))
    for x, y in ((0.05, 0.05), (1.1, 0.05), (0.05, 0.7), (1.1, 0.7)):
        m.add(box((x, y, 0), (x + 0.05, y + 0.05, 0.7)))
    return m


def bunny(n):
    rng = np.random.default_rng(7)
    waves = [(rng.normal(size=3), rng.uniform(1.5, 4.0), rng.uniform(0, 6.3), rng.uniform(0.02, 0.06))
             for _ in range(12)]

    def bumps(d):
        s = 1.0
        for k, f, ph, a in waves:
            s += a * math.sin(f * float(np.dot(d, k / np.linalg.norm(k))) * 3 + ph)
        return s

    m = sphere((0, 0, 0.05), 0.05, n, bumps)
    ear = sphere((0, 0, 0), 0.012, n // 2)
    ear.v = [(x * 1.0 - 0.015, y * 0.6, z * 3.0 + 0.12) for x, y, z in ear.v]
    m.add(ear)
    ear2 = sphere((0, 0, 0), 0.012, n // 2)
    ear2.v = [(x * 1.0 + 0.015, y * 0.6, z * 3.0 + 0.12) for x, y, z in ear2.v]
    m.add(ear2)
    tail = sphere((-0.055, 0, 0.03), 0.012, n // 2)
    return m.add(tail)


def l_bracket():
    poly = [(0.01, 0.01), (0.1, 0.01), (0.1, 0.0), (0.0, 0.0), (0.0, 0.08), (0.01, 0.08)]
    return extrude(poly, 0, 0.04)


def terrain(n):
    size, base = 1.0, -0.1

    def h(x, y):
        return 0.08 * math.sin(3 * x) * math.cos(2 * y) + 0.05 * math.sin(7 * x + 1) * math.sin(5 * y)

    m = Mesh()
    for i in range(n + 1):
        for j in range(n + 1):
            x, y = size * i / n, size * j / n
            m.v.append((x, y, h(x, y)))
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            m.f.append((a, b, b + 1))
            m.f.append((a, b + 1, a + 1))
    # Walls and bottom.
    ring = [i * (n + 1) for i in range(n + 1)] + [n * (n + 1) + j for j in range(1, n + 1)]
    ring += [i * (n + 1) + n for i in range(n - 1, -1, -1)] + [j for j in range(n - 1, 0, -1)]
    bottom = []
    for k in ring:
        x, y, _ = m.v[k]
        bottom.append(len(m.v))
        m.v.append((x, y, base))
    c = len(m.v)
    m.v.append((size / 2, size / 2, base))
    L = len(ring)
    for k in range(L):
        a, b = ring[k], ring[(k + 1) % L]
        a2, b2 = bottom[k], bottom[(k + 1) % L]
        m.f.append((a, a2, b2))
        m.f.append((a, b2, b))
        m.f.append((c, b2, a2))
    return m


def bowl(segments):
    prof = [(0, 0.0), (0.03, 0.0), (0.06, 0.03), (0.07, 0.05), (0.065, 0.05), (0.055, 0.032),
            (0.028, 0.006), (0, 0.006)]
    return lathe(list(reversed(prof)), segments)


def u_channel():
    poly = [(0.0, 0.0), (0.1, 0.0), (0.1, 0.08), (0.09, 0.08), (0.09, 0.01), (0.01, 0.01),
            (0.01, 0.08), (0.0, 0.08)]
    # Not star-shaped from one vertex: two prisms that overlap at the bottom plate.
    m = extrude([(0.0, 0.0), (0.1, 0.0), (0.1, 0.01), (0.0, 0.01)], 0, 0.3)
    m.add(extrude([(0.0, 0.0), (0.01, 0.0), (0.01, 0.08), (0.0, 0.08)], 0, 0.3))
    m.add(extrude([(0.09, 0.0), (0.1, 0.0), (0.1, 0.08), (0.09, 0.08)], 0, 0.3))
    del poly
    return m


def star(points):
    poly = [(0.0, 0.0)]
    ring = []
    for k in range(2 * points):
        r = 0.05 if k % 2 == 0 else 0.02
        t = math.pi * k / points
        ring.append((r * math.cos(t), r * math.sin(t)))
    # Fan from the centre: the centre first, then the ring (star-shaped from the centre).
    m = Mesh()
    n = len(ring)
    m.v = [(0, 0, 0), (0, 0, 0.02)] + [(x, y, 0) for x, y in ring] + [(x, y, 0.02) for x, y in ring]
    for k in range(n):
        k2 = (k + 1) % n
        m.f.append((0, 2 + k2, 2 + k))
        m.f.append((1, 2 + n + k, 2 + n + k2))
        m.f.append((2 + k, 2 + k2, 2 + n + k2))
        m.f.append((2 + k, 2 + n + k2, 2 + n + k))
    del poly
    return m


def hook(n):
    m = torus(0.04, 0.006, n, 12, arc=1.5 * math.pi, caps=True)
    return m


def dumbbell(n):
    m = sphere((0, 0, 0), 0.03, n)
    m.add(sphere((0.2, 0, 0), 0.03, n))

    def pt(i, j):
        t = 2 * math.pi * j / 16
        return (0.2 * i / 8, 0.01 * math.cos(t), 0.01 * math.sin(t))

    bar = grid_surface(8, 16, pt, False, True)
    # Close the bar's ends inside the spheres.
    for end, flip in ((0, False), (8, True)):
        c = len(bar.v)
        bar.v.append((0.2 * end / 8, 0, 0))
        for j in range(16):
            a, b = end * 16 + j, end * 16 + (j + 1) % 16
            bar.f.append((c, b, a) if flip else (c, a, b))
    bar.f = [(a, c, b) for a, b, c in bar.f]
    return m.add(bar)


def write_obj(m, path):
    with open(path, "w") as f:
        for v in m.v:
            f.write("v %.9g %.9g %.9g\n" % tuple(v))
        for a, b, c in m.f:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def write_stl(m, path):
    with open(path, "wb") as f:
        f.write(b"urlab bench".ljust(80, b" "))
        f.write(struct.pack("<I", len(m.f)))
        for a, b, c in m.f:
            f.write(struct.pack("<3f", 0, 0, 0))
            for k in (a, b, c):
                f.write(struct.pack("<3f", *m.v[k]))
            f.write(b"\0\0")


def write_ply(m, path):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
                "end_header\n" % (len(m.v), len(m.f)))
        for v in m.v:
            f.write("%.9g %.9g %.9g\n" % tuple(v))
        for a, b, c in m.f:
            f.write("3 %d %d %d\n" % (a, b, c))


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    out = sys.argv[1]
    small = "--small" in sys.argv[2:]
    os.makedirs(out, exist_ok=True)
    k = 0.25 if small else 1.0
    meshes = [
        ("mug.obj", mug(24, 4) if small else mug(160, 36)),
        ("chair.obj", chair()),
        ("table.obj", table()),
        ("torus.obj", torus(0.05, 0.015, int(48 * k) + 8, int(24 * k) + 8)),
        ("bunny.stl", bunny(int(48 * k) + 8)),
        ("l_bracket.obj", l_bracket()),
        ("terrain.ply", terrain(int(40 * k) + 8)),
        ("bowl.obj", bowl(int(96 * k) + 16)),
        ("u_channel.obj", u_channel()),
        ("star.obj", star(6)),
        ("hook.obj", hook(int(48 * k) + 12)),
        ("dumbbell.obj", dumbbell(int(24 * k) + 8)),
    ]
    for name, m in meshes:
        path = os.path.join(out, name)
        {"obj": write_obj, "stl": write_stl, "ply": write_ply}[name.rsplit(".", 1)[1]](m, path)
        print("%-14s %6d triangles" % (name, len(m.f)))


if __name__ == "__main__":
    main()
