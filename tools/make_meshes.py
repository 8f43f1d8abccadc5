#!/usr/bin/env python3
"""Writes the small mesh files used by pbrt-scenes/ (our own geometry, no third-party data).

icosphere.ply (ASCII, normals, u v), slab_be.ply (binary big-endian, quads, s t),
cube.obj, pbrt-scenes/v3/geometry/pool-water.pbrt (the pool scene's rippled water),
and pbrt-scenes/verify/geometry/swept-hyperboloid.ply (the surface a
hyperboloid's segment sweeps, finely tessellated with its normals: the reference for
`--fix hyperboloid-surface`). Run from the repository root: python3 tools/make_meshes.py
"""
import math, struct, os

def icosphere(subdiv=1):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdiv):
        cache, nf = {}, []
        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in cache:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                cache[k] = len(v) - 1
            return cache[k]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f

def write_ascii_ply(path):
    v, f = icosphere(1)
    with open(path, "w") as out:
        out.write("ply\nformat ascii 1.0\ncomment pbrt-sppm test mesh\n")
        out.write(f"element vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n")
        out.write("property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n")
        out.write(f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
        for x, y, z in v:
            u = 0.5 + math.atan2(y, x) / (2 * math.pi)
            out.write(f"{x:.6f} {y:.6f} {z:.6f} {x:.6f} {y:.6f} {z:.6f} {u:.6f} {0.5 + z / 2:.6f}\n")
        for a, b, c in f:
            out.write(f"3 {a} {b} {c}\n")

def write_binary_quads(path, n=4):
    verts = [(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)]
    quads = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i)
             for j in range(n) for i in range(n)]
    head = (f"ply\nformat binary_big_endian 1.0\nelement vertex {len(verts)}\n"
            "property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n"
            f"element face {len(quads)}\nproperty list uchar int vertex_indices\nproperty int face_indices\nend_header\n")
    with open(path, "wb") as out:
        out.write(head.encode())
        for x, y, z in verts:
            out.write(struct.pack(">5f", x, y, z, x, y))
        for k, q in enumerate(quads):
            out.write(struct.pack(">B4ii", 4, *q, k))

def write_obj(path):
    c = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    faces = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]
    with open(path, "w") as out:
        out.write("# unit cube\no cube\n")
        out.writelines(f"v {x} {y} {z}\n" for x, y, z in c)
        out.writelines("f " + " ".join(map(str, f)) + "\n" for f in faces)

def write_swept_hyperboloid(path, p1=(0.9, 0.0, -0.2), p2=(-0.2, 0.7, 1.2), nu=96, nv=32):
    """p(u, v) = rotate_z(2πu) · ((1 − v) p1 + v p2), with the normal ∂p/∂u × ∂p/∂v."""
    pts, nrm = [], []
    d = [b - a for a, b in zip(p1, p2)]
    for j in range(nv + 1):
        pr = [a + j / nv * e for a, e in zip(p1, d)]
        for i in range(nu + 1):
            c, s = math.cos(2 * math.pi * i / nu), math.sin(2 * math.pi * i / nu)
            p = (pr[0] * c - pr[1] * s, pr[0] * s + pr[1] * c, pr[2])
            du = (-p[1], p[0], 0.0)
            dv = (d[0] * c - d[1] * s, d[0] * s + d[1] * c, d[2])
            n = (du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2], du[0] * dv[1] - du[1] * dv[0])
            length = math.sqrt(sum(x * x for x in n))
            pts.append(p)
            nrm.append(tuple(x / length for x in n))
    faces = []
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            faces += [(a, a + 1, a + nu + 2), (a, a + nu + 2, a + nu + 1)]
    header = (f"ply\nformat binary_little_endian 1.0\ncomment the surface the hyperboloid p1 {p1} p2 {p2} sweeps\n"
              f"element vertex {len(pts)}\n" + "".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz"))
              + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as out:
        out.write(header.encode())
        for p, n in zip(pts, nrm):
            out.write(struct.pack("<6f", *p, *n))
        for f in faces:
            out.write(struct.pack("<B3i", 3, *f))

def write_pool_water(path, n=40):
    """The rippled water surface of pbrt-scenes/v3/pool.pbrt: an n x n grid over
    [-2, 2]^2 at height h(x, z) (three crossing sine waves), with its exact normals,
    as a pbrt trianglemesh to Include."""
    waves = [(0.04, 3.1, 1.7, 0.0), (0.03, -2.3, 4.1, 1.0), (0.02, 5.3, -3.7, 2.0)]
    def h(x, z):
        return sum(a * math.sin(kx * x + kz * z + ph) for a, kx, kz, ph in waves)
    def grad(x, z):
        c = [(a * math.cos(kx * x + kz * z + ph), kx, kz) for a, kx, kz, ph in waves]
        return sum(v * kx for v, kx, _ in c), sum(v * kz for v, _, kz in c)
    pts, nrm, idx = [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = -2 + 4 * i / n, -2 + 4 * j / n
            pts.append((x, h(x, z), z))
            dx, dz = grad(x, z)
            l = math.sqrt(dx * dx + 1 + dz * dz)
            nrm.append((-dx / l, 1 / l, -dz / l))
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            idx += [a, a + n + 2, a + 1, a, a + n + 1, a + n + 2]
    fmt = lambda v: " ".join("%.5g" % c for c in v)
    rows = lambda vs, k: "\n".join("    " + "  ".join(fmt(v) for v in vs[i:i + k]) for i in range(0, len(vs), k))
    ind = "\n".join("    " + " ".join(map(str, idx[i:i + 24])) for i in range(0, len(idx), 24))
    with open(path, "w") as out:
        out.write(f"# Written by tools/make_meshes.py (write_pool_water): {n} x {n} grid.\n")
        out.write(f'Shape "trianglemesh"\n  "point3 P" [\n{rows(pts, 6)} ]\n')
        out.write(f'  "normal N" [\n{rows(nrm, 6)} ]\n  "integer indices" [\n{ind} ]\n')

if __name__ == "__main__":
    for d in ("pbrt-scenes/v3/geometry", "pbrt-scenes/v4/geometry"):
        os.makedirs(d, exist_ok=True)
        write_ascii_ply(f"{d}/icosphere.ply")
        write_binary_quads(f"{d}/slab_be.ply")
        write_obj(f"{d}/cube.obj")
    write_swept_hyperboloid("pbrt-scenes/verify/geometry/swept-hyperboloid.ply")
    write_pool_water("pbrt-scenes/v3/geometry/pool-water.pbrt")
