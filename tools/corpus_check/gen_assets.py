#!/usr/bin/env python3
"""Generate the tiny binary assets used by tests/data/mjcf/corpus (stdlib only).

Run from the repository root:  python3 tools/corpus_check/gen_assets.py
The output is deterministic; the generated files are committed, so this script
only needs to be re-run when the assets are meant to change.

Layout (relative to tests/data/mjcf/corpus/assets/):
  meshes/tetra.stl      binary STL, tetrahedron (4 triangles)
  meshes/wedge.stl      binary STL, triangular prism (8 triangles, shared vertices repeated)
  meshes/octa.obj       Wavefront OBJ, octahedron with vt and vn
  meshes/pyramid.obj    Wavefront OBJ, square pyramid, positions and faces only
  meshes/box.msh        MuJoCo MSH binary, box with normals and texcoords
  meshes/strip.skn      MuJoCo SKN binary skin (bones: skin_a, skin_b)
  textures/checker.png  16x16 RGB (2d)
  textures/cube.png     8x8 RGB (cube, repeated on all sides)
  textures/grid.png     16x12 RGB (cube from a 3x4 grid, layout .U..LFRB.D..)
  textures/face_*.png   4x4 RGB, one per cube side (right left up down front back)
  textures/sky.png      8x8 RGB (skybox)
  textures/gray.png     8x8 grayscale PNG (color type 0) used as a 2d texture
  textures/custom.tex   MuJoCo custom texture binary (int32 w, int32 h, rgb bytes)
  hfields/terrain.png   9x7 grayscale PNG height field
  hfields/terrain.bin   MuJoCo custom height field binary (int32 nrow, int32 ncol, float32 data)
"""
import math
import os
import struct
import zlib

ROOT = os.path.join("tests", "data", "mjcf", "corpus", "assets")


def out(rel, data):
    path = os.path.join(ROOT, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    assert len(data) < 50 * 1024, rel


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def orient(verts, faces):
    """Make every face of a convex solid counter-clockwise seen from outside."""
    c = [sum(v[i] for v in verts) / len(verts) for i in range(3)]
    res = []
    for f in faces:
        a, b, d = (verts[i] for i in f)
        n = cross(sub(b, a), sub(d, a))
        fc = [(a[i] + b[i] + d[i]) / 3 for i in range(3)]
        res.append(tuple(f) if dot(n, sub(fc, c)) > 0 else (f[0], f[2], f[1]))
    return res


def stl(verts, faces):
    data = bytearray(b"URLab corpus binary STL".ljust(80, b" "))
    data += struct.pack("<I", len(faces))
    for f in faces:
        a, b, d = (verts[i] for i in f)
        n = cross(sub(b, a), sub(d, a))
        ln = math.sqrt(dot(n, n))
        data += struct.pack("<3f", *[x / ln for x in n])
        for v in (a, b, d):
            data += struct.pack("<3f", *v)
        data += struct.pack("<H", 0)
    return bytes(data)


def png(width, height, rows, gray=False):
    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body +
                struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0 if gray else 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def rgb_image(w, h, fn):
    rows = []
    for y in range(h):
        r = []
        for x in range(w):
            r += list(fn(x, y))
        rows.append(r)
    return rows


def main():
    # --- STL tetrahedron
    tv = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]
    tf = orient(tv, [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)])
    out("meshes/tetra.stl", stl(tv, tf))

    # --- STL wedge (triangular prism along y)
    wv = [[-0.1, -0.05, 0], [0.1, -0.05, 0], [0, -0.05, 0.08],
          [-0.1, 0.05, 0], [0.1, 0.05, 0], [0, 0.05, 0.08]]
    wf = orient(wv, [(0, 1, 2), (3, 4, 5), (0, 1, 4), (0, 4, 3),
                     (1, 2, 5), (1, 5, 4), (2, 0, 3), (2, 3, 5)])
    out("meshes/wedge.stl", stl(wv, wf))

    # --- OBJ octahedron with texcoords and normals (one vt/vn per vertex)
    ov = [[0.06, 0, 0], [-0.06, 0, 0], [0, 0.06, 0], [0, -0.06, 0], [0, 0, 0.06], [0, 0, -0.06]]
    of = orient(ov, [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4),
                     (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)])
    vt = [(1, 0.5), (0, 0.5), (0.5, 1), (0.5, 0), (0.5, 0.5), (0.25, 0.25)]
    lines = ["# URLab corpus: octahedron with texcoords and normals"]
    lines += ["v %g %g %g" % tuple(v) for v in ov]
    lines += ["vt %g %g" % t for t in vt]
    lines += ["vn %g %g %g" % tuple(x / 0.06 for x in v) for v in ov]
    lines += ["f %d/%d/%d %d/%d/%d %d/%d/%d" % tuple(i + 1 for i in (a, a, a, b, b, b, c, c, c))
              for a, b, c in of]
    out("meshes/octa.obj", ("\n".join(lines) + "\n").encode())

    # --- OBJ square pyramid, positions and faces only (quad base split in two)
    pv = [[-0.05, -0.05, 0], [0.05, -0.05, 0], [0.05, 0.05, 0], [-0.05, 0.05, 0], [0, 0, 0.07]]
    pf = orient(pv, [(0, 1, 2), (0, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)])
    lines = ["# URLab corpus: square pyramid", "o pyramid"]
    lines += ["v %g %g %g" % tuple(v) for v in pv]
    lines += ["f %d %d %d" % tuple(i + 1 for i in f) for f in pf]
    out("meshes/pyramid.obj", ("\n".join(lines) + "\n").encode())

    # --- MSH box with normals and texcoords
    bv = [[x, y, z] for x in (-0.04, 0.04) for y in (-0.03, 0.03) for z in (-0.02, 0.02)]
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    bf = []
    for q in quads:
        bf += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    bf = orient(bv, bf)
    bn = [[v[0] / 0.04, v[1] / 0.03, v[2] / 0.02] for v in bv]
    bt = [((i & 4) / 4.0, (i & 2) / 2.0) for i in range(8)]
    data = struct.pack("<4i", len(bv), len(bn), len(bt), len(bf))
    for v in bv:
        data += struct.pack("<3f", *v)
    for n in bn:
        data += struct.pack("<3f", *n)
    for t in bt:
        data += struct.pack("<2f", *t)
    for f in bf:
        data += struct.pack("<3i", *f)
    out("meshes/box.msh", data)

    # --- SKN skin: a closed box around two bodies skin_a (x<0) and skin_b (x>0).
    # Vertices are global; bind poses equal the bodies' global poses in the model
    # (skin_a at (-0.1, 0, 1), skin_b at (0.1, 0, 1)).
    sv = [[x, y, 1 + z] for x in (-0.2, 0.2) for y in (-0.05, 0.05) for z in (-0.05, 0.05)]
    sf = []
    for q in quads:
        sf += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    sf = orient(sv, sf)
    data = struct.pack("<4i", len(sv), 0, len(sf), 2)
    for v in sv:
        data += struct.pack("<3f", *v)
    for f in sf:
        data += struct.pack("<3i", *f)
    for name, pos, ids in ((b"skin_a", (-0.1, 0, 1), (0, 1, 2, 3)),
                           (b"skin_b", (0.1, 0, 1), (4, 5, 6, 7))):
        data += name.ljust(40, b"\x00")
        data += struct.pack("<3f", *pos) + struct.pack("<4f", 1, 0, 0, 0)
        data += struct.pack("<i", len(ids)) + struct.pack("<%di" % len(ids), *ids)
        data += struct.pack("<%df" % len(ids), *([1.0] * len(ids)))
    out("meshes/strip.skn", data)

    # --- textures
    out("textures/checker.png", png(16, 16, rgb_image(
        16, 16, lambda x, y: (220, 220, 220) if ((x // 4) + (y // 4)) % 2 else (40, 60, 90))))
    out("textures/cube.png", png(8, 8, rgb_image(
        8, 8, lambda x, y: (30 * x, 30 * y, 128))))
    cell = {"U": (250, 250, 250), "L": (200, 40, 40), "F": (40, 200, 40),
            "R": (40, 40, 200), "B": (200, 200, 40), "D": (60, 60, 60), ".": (0, 0, 0)}
    layout = ".U..LFRB.D.."
    out("textures/grid.png", png(16, 12, rgb_image(
        16, 12, lambda x, y: cell[layout[(y // 4) * 4 + x // 4]])))
    faces = {"right": (255, 0, 0), "left": (0, 255, 255), "up": (0, 255, 0),
             "down": (255, 0, 255), "front": (0, 0, 255), "back": (255, 255, 0)}
    for nm, col in faces.items():
        out("textures/face_%s.png" % nm, png(4, 4, rgb_image(
            4, 4, lambda x, y, c=col: c if (x + y) % 3 else (128, 128, 128))))
    out("textures/sky.png", png(8, 8, rgb_image(
        8, 8, lambda x, y: (100 + 15 * y, 150 + 10 * y, 255))))
    out("textures/gray.png", png(8, 8, [[(x * 37 + y * 11) % 256 for x in range(8)]
                                        for y in range(8)], gray=True))
    w, h = 4, 2
    data = struct.pack("<2i", w, h) + bytes(
        sum(([(60 * x) % 256, (90 * y) % 256, 200] for y in range(h) for x in range(w)), []))
    out("textures/custom.tex", data)

    # --- height fields
    nr, nc = 7, 9
    out("hfields/terrain.png", png(nc, nr, [[int(127 + 120 * math.sin(x / 2.0) * math.cos(y / 2.0))
                                              for x in range(nc)] for y in range(nr)], gray=True))
    nr, nc = 5, 6
    data = struct.pack("<2i", nr, nc)
    for y in range(nr):
        for x in range(nc):
            data += struct.pack("<f", 0.5 + 0.5 * math.sin(0.9 * x + 0.4 * y))
    out("hfields/terrain.bin", data)


if __name__ == "__main__":
    main()
