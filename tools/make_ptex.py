#!/usr/bin/env python3
"""Writes the Ptex test textures and the meshes they belong to (our own Ptex writer).

    python3 tools/make_ptex.py [OUT_DIR]     # default pbrt-scenes/verify

Writes OUT_DIR/textures/ptex-{grid,cube,fan,tri}.ptx and OUT_DIR/geometry/ptex-{v3,v4}.pbrt
(the three meshes as pbrt-v3 triangle meshes and pbrt-v4 bilinear patch meshes, with
`faceIndices` and per-face uv). Standard library only.

The files follow Ptex's format version 1 (minor version 4) as the Ptex library's
writer makes them: level 0 with every face (zlib; 8- and 16-bit data as byte
differences; faces over 128 KiB in tiles), reduction levels for faces whose smaller
side is at least 8, each halving the one before by Ptex's box filter in the data
type, a constant value per face (the mean of its smallest level), and the "constant
neighbourhood" flags. The meshes' topology gives each face's neighbours and the
edges it meets them by; several faces are turned in their mesh so that the filter
must rotate its kernel to cross their edges.

- grid: 3 x 3 quads, RGB uint8, sides of 2 to 256 texels (a 256 x 256 face in tiles,
  16 x 8 and 8 x 16 faces, a constant face), corners of valence 4 inside and mesh
  borders around; checks and gradients of a hue per face.
- cube: 6 quads, RGB half, corners of valence 3; one face replaced by an appended
  edit (as Ptex's incremental writer writes it).
- fan: 5 quads around a corner of valence 5, 1 channel float.
- tri: an octahedron's 8 triangles (a triangle-mesh Ptex file), RGB uint16.
"""
import math
import os
import struct
import sys
import zlib

TILE_SIZE = 65536
MIN_REDUCTION_LOG2 = 2
BOTTOM, RIGHT, TOP, LEFT = range(4)
TYPES = {"u8": (0, "B", 1), "u16": (1, "H", 2), "half": (2, "e", 2), "float": (3, "f", 4)}


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def store(dt, x):
    """x as the data type holds it (Ptex's T(x): integers truncate)."""
    if dt in ("u8", "u16"):
        return int(x)
    return struct.unpack("<" + TYPES[dt][1], struct.pack("<" + TYPES[dt][1], x))[0]


class Texture:
    def __init__(self, dt, nchan, faces, triangles=False):
        """faces: list of dicts with res (ulog2, vlog2), texels (list of tuples, row by row
        from v = 0), adjfaces, adjedges (unused 4th entries for triangles)."""
        self.dt, self.nchan, self.faces, self.triangles = dt, nchan, faces, triangles
        self.psize = TYPES[dt][2] * nchan

    def pack(self, pixels):
        """Interleaved pixels as planes of channels (Ptex's deinterleave)."""
        fmt = TYPES[self.dt][1]
        vals = [p[c] for c in range(self.nchan) for p in pixels]
        return struct.pack("<%d%s" % (len(vals), fmt), *vals)

    def block(self, pixels):
        """One zipped block: (encoding, bytes)."""
        raw = self.pack(pixels)
        if self.dt in ("u8", "u16"):
            fmt = TYPES[self.dt][1]
            n = len(raw) // TYPES[self.dt][2]
            vals = struct.unpack("<%d%s" % (n, fmt), raw)
            mask = 0xFF if self.dt == "u8" else 0xFFFF
            diffs = [(v - p) & mask for v, p in zip(vals, (0,) + vals[:-1])]
            return 2, zlib.compress(struct.pack("<%d%s" % (n, fmt), *diffs))
        return 1, zlib.compress(raw)

    def face_data(self, pixels, res):
        """A face's data: (header word, bytes), tiled where Ptex's writer tiles."""
        tres = self.tile_res(res)
        if tres == res:
            enc, data = self.block(pixels)
            return len(data) | enc << 30, data
        tu, tv = 1 << tres[0], 1 << tres[1]
        w = 1 << res[0]
        headers, body = [], b""
        for ty in range((1 << res[1]) // tv):
            for tx in range(w // tu):
                tile = [pixels[(ty * tv + y) * w + tx * tu + x] for y in range(tv) for x in range(tu)]
                if all(p == tile[0] for p in tile):
                    data = self.pack([tile[0]])
                    headers.append(len(data))
                else:
                    enc, data = self.block(tile)
                    headers.append(len(data) | enc << 30)
                body += data
        zh = zlib.compress(struct.pack("<%dI" % len(headers), *headers))
        data = struct.pack("<bbI", tres[0], tres[1], len(zh)) + zh + body
        return len(data) | 3 << 30, data

    def tile_res(self, res):
        size = (1 << res[0]) * (1 << res[1]) * self.psize
        q = size // TILE_SIZE
        ntiles_log2 = q.bit_length() - 1 if q > 0 else 0
        if ntiles_log2 == 0:
            return res
        n = res[0] + res[1] - ntiles_log2
        tu = min((n + 1) // 2, res[0])
        return (tu, min(n - tu, res[1]))

    def reduce(self, pixels, res):
        """Ptex's `reduce` (2 x 2 means in the data type), or for triangles `reduceTri`
        (three texels of a triangle and the one of the flipped triangle across them)."""
        w, h = 1 << res[0], 1 << res[1]
        out = []
        for y in range(0, h, 2):
            for x in range(0, w, 2):
                q = [pixels[y * w + x], pixels[y * w + x + 1], pixels[(y + 1) * w + x], pixels[(y + 1) * w + x + 1]]
                if self.triangles:
                    q[3] = pixels[(w - 1 - x) * w + w - 1 - y]
                if self.dt in ("u8", "u16"):
                    out.append(tuple((a + b + c + d) >> 2 for a, b, c, d in zip(*q)))
                else:
                    out.append(tuple(store(self.dt, 0.25 * f32(f32(f32(a + b) + c) + d)) for a, b, c, d in zip(*q)))
        return out

    def average(self, pixels):
        """Ptex's `average`: a float sum times 1/n, stored in the data type."""
        sums = [0.0] * self.nchan
        for p in pixels:
            sums = [f32(s + v) for s, v in zip(sums, p)]
        scale = f32(1.0 / len(pixels))
        return tuple(store(self.dt, f32(s * scale)) for s in sums)


def min_side(face):
    return 1 if face["constant"] else min(face["res"])


def write(path, tex, edit=None):
    """Writes the texture; `edit` = (face id, new face dict) appends a face edit."""
    faces = tex.faces
    const = []
    for f in faces:
        f["constant"] = all(p == f["texels"][0] for p in f["texels"])
        const.append(f["texels"][0] if f["constant"] else None)
    # Level 0, by face id.
    level0 = []
    reductions = {}
    for i, f in enumerate(faces):
        if f["constant"]:
            level0.append((0, b""))
            continue
        level0.append(tex.face_data(f["texels"], f["res"]))
        if min(f["res"]) > MIN_REDUCTION_LOG2:
            reductions[i] = tex.reduce(f["texels"], f["res"])
        else:
            const[i] = tex.average(f["texels"])
    # Reduction levels, in Ptex's order (stable, by decreasing smaller side).
    order = sorted(range(len(faces)), key=lambda i: -min_side(faces[i]))
    sizes = []
    cutoff = MIN_REDUCTION_LOG2
    for r in range(len(order) - 1, -1, -1):
        m = min_side(faces[order[r]])
        while m > cutoff:
            sizes.append(r + 1)
            cutoff += 1
    levels = [level0]
    for li, size in enumerate(sizes, start=1):
        nxt = sizes[li] if li < len(sizes) else 0
        level = []
        for r in range(size):
            i = order[r]
            res = (faces[i]["res"][0] - li, faces[i]["res"][1] - li)
            data = reductions[i]
            level.append(tex.face_data(data, res))
            if r < nxt:
                reductions[i] = tex.reduce(data, res)
            else:
                const[i] = tex.average(data)
        levels.append(level)
    flags = [(1 if f["constant"] else 0) for f in faces]
    for i in neighbourhood_constant(faces, const):
        flags[i] |= 4
    info = b"".join(
        struct.pack("<bbBB4i", *f["res"], sum((e & 3) << 2 * k for k, e in enumerate(f["adjedges"])), flags[i], *f["adjfaces"])
        for i, f in enumerate(faces)
    )
    zinfo = zlib.compress(info)
    fmt = TYPES[tex.dt][1]
    zconst = zlib.compress(b"".join(struct.pack("<%d%s" % (tex.nchan, fmt), *c) for c in const))
    level_blobs, level_info = [], []
    for level in levels:
        zh = zlib.compress(struct.pack("<%dI" % len(level), *[h for h, _ in level]))
        blob = zh + b"".join(d for _, d in level)
        level_blobs.append(blob)
        level_info.append(struct.pack("<QII", len(blob), len(zh), len(level)))
    edits = b"" if edit is None else face_edit(tex, *edit)
    # The 8 zero bytes after the (empty) metadata are Ptex's "compatibility barrier":
    # readers look for edits after it.
    body = zinfo + zconst + b"".join(level_info) + b"".join(level_blobs) + bytes(8)
    edit_at = 64 + 40 + len(body)
    header = struct.pack(
        "<IIIIiHHIIIIIIQII", struct.unpack("<I", b"Ptex")[0], 1, 0 if tex.triangles else 1, TYPES[tex.dt][0], -1, tex.nchan,
        len(levels), len(faces), 40, len(zinfo), len(zconst), 16 * len(levels), 4,
        sum(len(b) for b in level_blobs), 0, 0,
    )
    ext = struct.pack("<HHHHIIQQQ", 0, 0, 0, 0, 0, 0, 0, len(edits), edit_at)
    with open(path, "wb") as out:
        out.write(header + ext + body + edits)


def face_edit(tex, faceid, f):
    """An edit replacing face `faceid` (Ptex's incremental writer's record)."""
    word, data = tex.face_data(f["texels"], f["res"])
    edges = sum((e & 3) << 2 * k for k, e in enumerate(f["adjedges"]))
    rec = struct.pack("<IbbBB4iI", faceid, *f["res"], edges, 0, *f["adjfaces"], word)
    fmt = TYPES[tex.dt][1]
    rec += struct.pack("<%d%s" % (tex.nchan, fmt), *tex.average(f["texels"])) + data
    return struct.pack("<BI", 0, len(rec)) + rec


def neighbourhood_constant(faces, const):
    """Constant faces whose neighbours around every corner hold the same constant
    (Ptex's flagConstantNeighorhoods, for quads without subfaces)."""
    out = []
    for i, f in enumerate(faces):
        if not f["constant"]:
            continue
        ok = True
        for eid in range(4):
            afid, aeid, count = f["adjfaces"][eid], f["adjedges"][eid], 0
            while ok and afid != i and afid >= 0 and count + 1 < 10:
                count += 1
                af = faces[afid]
                if not af["constant"] or const[afid] != const[i]:
                    ok = False
                    break
                aeid = (aeid + 1) % 4
                afid, aeid = af["adjfaces"][aeid], af["adjedges"][aeid]
            if ok and afid < 0:
                aeid = (aeid - 1 + 4) % 4
                afid, aeid = f["adjfaces"][aeid], f["adjedges"][aeid]
                count = 0
                while afid != i and afid >= 0 and count + 1 < 10:
                    count += 1
                    af = faces[afid]
                    if not af["constant"] or const[afid] != const[i]:
                        ok = False
                        break
                    aeid = (aeid - 1 + 4) % 4
                    afid, aeid = af["adjfaces"][aeid], af["adjedges"][aeid]
            if not ok:
                break
        if ok:
            out.append(i)
    return out


def adjacency(polys):
    """Each face's neighbours and edges, from its corners: quads (v00, v10, v11, v01),
    triangles (uv (0, 0), (1, 0), (0, 1))."""
    edges = {}
    for q, c in enumerate(polys):
        for e in range(len(c)):
            edges[(c[e], c[(e + 1) % len(c)])] = (q, e)
    out = []
    for c in polys:
        faces, eids = [-1] * 4, [0] * 4
        for e in range(len(c)):
            faces[e], eids[e] = edges.get((c[(e + 1) % len(c)], c[e]), (-1, 0))
        out.append((faces, eids))
    return out


def hue(h):
    """A colour of hue h in [0, 1), kept away from saturation (pbrt-v4's spectral
    upsampling of nearly pure colours is not what the test is about)."""
    return [0.65 + 0.35 * math.cos(2 * math.pi * (h - k / 3)) for k in range(3)]


def pattern(i, res, scale, dt, turn=0.0):
    """Face i's texels: checks of 2 texels over a gradient, in the face's hue."""
    w, h = 1 << res[0], 1 << res[1]
    base = hue(0.13 * i + turn)
    px = []
    for y in range(h):
        for x in range(w):
            s, t = (x + 0.5) / w, (y + 0.5) / h
            check = 1.0 if ((x >> 1) + (y >> 1)) % 2 == 0 else 0.35
            v = [min(1.0, check * (0.25 + 0.75 * s) * (0.45 + 0.55 * t) * b + 0.08 * t) for b in base]
            px.append(tuple(store(dt, c * scale + (0.5 if dt in ("u8", "u16") else 0.0)) for c in v))
    return px


def grid_mesh():
    """3 x 3 quads on [0, 3]², some turned so their (0, 0) corner lies elsewhere."""
    pts = [(x, y) for y in range(4) for x in range(4)]
    quads = []
    turns = [0, 1, 0, 2, 0, 3, 1, 0, 2]
    for q in range(9):
        x, y = q % 3, q // 3
        c = [y * 4 + x, y * 4 + x + 1, (y + 1) * 4 + x + 1, (y + 1) * 4 + x]
        t = turns[q]
        quads.append(c[t:] + c[:t])
    return pts, quads


def cube_mesh():
    pts = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    turns = [0, 1, 2, 3, 1, 0]
    return pts, [q[t:] + q[:t] for q, t in zip(quads, turns)]


def fan_mesh():
    """5 quads around the origin: centre, edge midpoints and a pentagon's corners."""
    pts = [(0.0, 0.0)]
    for k in range(5):
        a = 2 * math.pi * k / 5
        pts.append((math.cos(a), math.sin(a)))
    for k in range(5):
        a = 2 * math.pi * (k + 0.5) / 5
        pts.append((1.25 * math.cos(a), 1.25 * math.sin(a)))
    quads = [[0, 1 + k, 6 + k, 1 + (k + 1) % 5] for k in range(5)]
    return pts, quads


def octahedron_mesh():
    """8 triangles with corners of valence 4, some turned."""
    pts = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    tris = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    turns = [0, 1, 2, 0, 1, 2, 0, 1]
    return pts, [t[k:] + t[:k] for t, k in zip(tris, turns)]


def textures():
    pts, quads = grid_mesh()
    res = [(3, 3), (4, 3), (3, 4), (2, 2), (4, 4), (5, 5), (8, 8), (1, 1), (3, 3)]
    adj = adjacency(quads)
    faces = []
    for i, (r, (af, ae)) in enumerate(zip(res, adj)):
        px = pattern(i, r, 255, "u8")
        if i == 8:
            px = [(200, 120, 40)] * len(px)
        faces.append({"res": r, "texels": px, "adjfaces": af, "adjedges": ae})
    grid = (Texture("u8", 3, faces), None)
    pts, quads = cube_mesh()
    faces = []
    for i, (af, ae) in enumerate(adjacency(quads)):
        r = [(4, 4), (3, 3), (5, 4), (3, 3), (4, 5), (2, 2)][i]
        faces.append({"res": r, "texels": pattern(i + 3, r, 1.0, "half"), "adjfaces": af, "adjedges": ae})
    new = dict(faces[2], res=(3, 4), texels=pattern(11, (3, 4), 1.0, "half", 0.5))
    cube = (Texture("half", 3, faces), (2, new))
    pts, quads = fan_mesh()
    faces = []
    for i, (af, ae) in enumerate(adjacency(quads)):
        r = [(3, 3), (4, 4), (3, 3), (2, 3), (3, 3)][i]
        px = [(store("float", sum(p) / 3),) for p in pattern(i, r, 1.0, "float", 0.2)]
        faces.append({"res": r, "texels": px, "adjfaces": af, "adjedges": ae})
    fan = (Texture("float", 1, faces), None)
    pts, tris = octahedron_mesh()
    faces = []
    for i, (af, ae) in enumerate(adjacency(tris)):
        r = [(3, 3), (4, 4), (3, 3), (2, 2), (4, 4), (3, 3), (5, 5), (3, 3)][i]
        faces.append({"res": r, "texels": pattern(i + 5, r, 65535, "u16"), "adjfaces": af, "adjedges": ae})
    tri = (Texture("u16", 3, faces, triangles=True), None)
    return {"grid": grid, "cube": cube, "fan": fan, "tri": tri}


def mesh_text(pts, quads, v4, place):
    """A mesh with 4 vertices per face (own uv) and `faceIndices`."""
    P, uv, idx, fi = [], [], [], []
    tris = len(quads[0]) == 3
    for q, c in enumerate(quads):
        base = len(P)
        for k, (u, v) in zip(c, [(0, 0), (1, 0), (0, 1)] if tris else [(0, 0), (1, 0), (1, 1), (0, 1)]):
            P.append(place(pts[k]))
            uv.append((u, v))
        if tris:
            idx += [base, base + 1, base + 2]
            fi.append(q)
        elif v4:
            idx += [base, base + 1, base + 3, base + 2]
            fi.append(q)
        else:
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
            fi += [q, q]
    num = lambda xs: " ".join("%.6g" % x for p in xs for x in p)
    kind = '"bilinearmesh"' if v4 and not tris else '"trianglemesh"'
    return (
        "Shape %s\n    \"point3 P\" [ %s ]\n    \"point2 uv\" [ %s ]\n    \"integer indices\" [ %s ]\n"
        "    \"integer faceIndices\" [ %s ]\n" % (kind, num(P), num(uv), " ".join(map(str, idx)), " ".join(map(str, fi)))
    )


def meshes(v4):
    g, c, f = grid_mesh(), cube_mesh(), fan_mesh()
    out = "# Written by tools/make_ptex.py: the meshes of ptex-{grid,cube,fan}.ptx.\n"
    out += "AttributeBegin\n    NamedMaterial \"grid\"\n"
    out += mesh_text(*g, v4, lambda p: (p[0] - 1.5, 0, p[1] - 1.5)) + "AttributeEnd\n"
    out += "AttributeBegin\n    NamedMaterial \"cube\"\n"
    out += mesh_text(*c, v4, lambda p: (0.3 + 0.7 * p[0], 0.7 * p[2], -0.6 + 0.7 * p[1])) + "AttributeEnd\n"
    out += "AttributeBegin\n    NamedMaterial \"fan\"\n"
    out += mesh_text(*f, v4, lambda p: (-0.8 + 0.55 * p[0], 0.75 + 0.55 * p[1], 0.35)) + "AttributeEnd\n"
    out += "AttributeBegin\n    NamedMaterial \"tri\"\n"
    o = octahedron_mesh()
    out += mesh_text(*o, v4, lambda p: (-0.75 + 0.45 * p[0], 0.45 + 0.45 * p[1], -0.7 + 0.45 * p[2])) + "AttributeEnd\n"
    return out


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "pbrt-scenes/verify"
    os.makedirs(os.path.join(out, "textures"), exist_ok=True)
    os.makedirs(os.path.join(out, "geometry"), exist_ok=True)
    for name, (tex, edit) in textures().items():
        write(os.path.join(out, "textures", "ptex-%s.ptx" % name), tex, edit)
    for v in (3, 4):
        with open(os.path.join(out, "geometry", "ptex-v%d.pbrt" % v), "w") as f:
            f.write(meshes(v == 4))


if __name__ == "__main__":
    main()
