#!/usr/bin/env python3
"""Render a `pbrt-sppm export --mitsuba` scene with Mitsuba 3's path tracer.

    pbrt-sppm export --mitsuba scene.pbrt > scene.json
    python3 tools/mitsuba_reference.py scene.json reference.exr --spp 1024

Needs the PyPI package `mitsuba` (its `scalar_rgb` variant needs no system libraries).
The JSON form is documented in src/cli/export.rs. Everything the export could not carry
over is printed as a warning first. Before rendering, the script checks that
Mitsuba's camera reproduces pbrt-sppm's rays (`check_rays`), so a mirrored or shifted
image is an error rather than a silent mismatch. Errors print
`file: error: message` and exit with status 1.
"""

import argparse
import json
import os
import struct
import sys
import tempfile
import time

FORMAT, VERSION = "pbrt-sppm-export", 1


class ExportError(Exception):
    pass


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def matrix(mi, row_major):
    return mi.ScalarTransform4f([[row_major[4 * r + c] for c in range(4)] for r in range(4)])


def twosided(bsdf):
    # pbrt's reflective BSDFs work on both sides; Mitsuba's only on the front.
    return {"type": "twosided", "bsdf": bsdf}


def material(m):
    t = m["type"]
    if t == "diffuse":
        return twosided({"type": "diffuse", "reflectance": rgb(m["reflectance"])})
    if t == "mirror":
        return twosided({"type": "conductor", "material": "none", "specular_reflectance": rgb(m["reflectance"])})
    if t == "conductor":
        return twosided({"type": "conductor", "eta": rgb(m["eta"]), "k": rgb(m["k"])})
    if t == "rough_conductor":
        au, av = m["alpha"]
        return twosided({"type": "roughconductor", "distribution": "ggx", "alpha_u": au, "alpha_v": av,
                         "eta": rgb(m["eta"]), "k": rgb(m["k"])})
    if t == "dielectric":
        return {"type": "dielectric", "int_ior": float(m["eta"]), "ext_ior": 1.0,
                "specular_reflectance": rgb(m["reflectance"]), "specular_transmittance": rgb(m["transmittance"])}
    if t == "thin_dielectric":
        return {"type": "thindielectric", "int_ior": float(m["eta"]), "ext_ior": 1.0}
    if t == "none":
        return {"type": "null"}
    raise ExportError(f"unknown material type \"{t}\"")


def write_ply(path, positions, normals, indices):
    """A binary little-endian PLY with x y z [nx ny nz] and triangle faces."""
    n_vert, n_face = len(positions) // 3, len(indices) // 3
    props = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals else [])
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {n_vert}"]
    header += [f"property float {p}" for p in props]
    header += [f"element face {n_face}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        per_vertex = struct.Struct("<" + "f" * len(props))
        for k in range(n_vert):
            values = positions[3 * k:3 * k + 3] + (normals[3 * k:3 * k + 3] if normals else [])
            f.write(per_vertex.pack(*values))
        face = struct.Struct("<B3i")
        for k in range(n_face):
            f.write(face.pack(3, *indices[3 * k:3 * k + 3]))


def shape(mi, s, materials, tmp, name):
    t = s["type"]
    if t == "sphere":
        d = {"type": "sphere", "center": s["center"], "radius": s["radius"], "flip_normals": s["flip_normals"]}
    elif t in ("cylinder", "disk"):
        d = {"type": t, "to_world": matrix(mi, s["to_world"]), "flip_normals": s["flip_normals"]}
    elif t == "mesh":
        if not s["indices"]:
            return None
        path = os.path.join(tmp, f"{name}.ply")
        write_ply(path, s["positions"], s["normals"], s["indices"])
        d = {"type": "ply", "filename": path, "face_normals": s["face_normals"]}
    else:
        raise ExportError(f"unknown shape type \"{t}\"")
    d["bsdf"] = materials[s["material"]]
    if s.get("emission"):
        d["emitter"] = {"type": "area", "radiance": rgb(s["emission"]["radiance"])}
    return d


def light(mi, l):
    t = l["type"]
    if t == "point":
        return {"type": "point", "position": l["position"], "intensity": rgb(l["intensity"])}
    if t == "spot":
        p, d = l["position"], l["direction"]
        target = [p[i] + d[i] for i in range(3)]
        return {"type": "spot", "to_world": mi.ScalarTransform4f().look_at(origin=p, target=target, up=l["up"]),
                "intensity": rgb(l["intensity"]), "cutoff_angle": l["cutoff_angle"], "beam_width": l["beam_width"]}
    if t == "distant":
        return {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
    if t == "constant":
        return {"type": "constant", "radiance": rgb(l["radiance"])}
    if t == "env_map":
        return {"type": "envmap", "filename": l["filename"], "to_world": matrix(mi, l["to_world"]),
                "scale": float(l["scale"])}
    raise ExportError(f"unknown light type \"{t}\"")


def sensor(mi, doc, spp):
    cam, film = doc["camera"], doc["film"]
    x0, x1, y0, y1 = film["crop"]
    # pbrt's camera space is left-handed (+x is image right); Mitsuba's +x is image left.
    to_world = matrix(mi, cam["world_from_camera"]) @ mi.ScalarTransform4f().scale([-1, 1, 1])
    d = {
        "film": {"type": "hdrfilm", "width": film["width"], "height": film["height"],
                 "crop_offset_x": x0, "crop_offset_y": y0, "crop_width": x1 - x0, "crop_height": y1 - y0,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32"},
        "sampler": {"type": "independent", "sample_count": spp},
    }
    if cam["kind"] == "orthographic":
        # Mitsuba spans [-1, 1] on x; pbrt spans [-1, 1] on the shorter axis.
        s = max(film["width"] / film["height"], 1.0)
        d.update({"type": "orthographic", "to_world": to_world @ mi.ScalarTransform4f().scale([s, s, 1])})
        return d
    d.update({"fov": cam["fov"], "fov_axis": "smaller", "to_world": to_world, "near_clip": 1e-4})
    if cam["lens_radius"] > 0:
        d.update({"type": "thinlens", "aperture_radius": cam["lens_radius"], "focus_distance": cam["focal_distance"]})
    else:
        d["type"] = "perspective"
    return d


def check_camera(mi, scene, doc):
    """Mitsuba's rays through the check positions must be pbrt-sppm's rays."""
    s = scene.sensors()[0]
    for c in doc["camera"]["check_rays"]:
        ray, _ = s.sample_ray(0.0, 0.5, mi.Point2f(*c["film_uv"]), mi.Point2f(0.5, 0.5))
        d = [float(x) for x in ray.d]
        o = [float(x) for x in ray.o]
        norm = sum(x * x for x in d) ** 0.5
        d = [x / norm for x in d]
        cos = sum(a * b for a, b in zip(d, c["d"]))
        off = [o[i] - c["o"][i] for i in range(3)]
        along = sum(off[i] * c["d"][i] for i in range(3))
        miss = sum((off[i] - along * c["d"][i]) ** 2 for i in range(3)) ** 0.5
        scale = 1e-4 * (1.0 + max(abs(x) for x in c["o"]))
        if cos < 1.0 - 1e-5 or miss > scale:
            raise ExportError(
                f"Mitsuba's camera ray at film position {c['film_uv']} is o={o} d={d}, "
                f"pbrt-sppm's is o={c['o']} d={c['d']}: the camera cannot be reproduced")


def build(mi, doc, tmp, spp):
    materials = [material(m) for m in doc["materials"]]
    d = {"type": "scene",
         # pbrt's maxdepth counts bounces; Mitsuba's max_depth counts path segments.
         "integrator": {"type": "path", "max_depth": int(doc["max_depth"]) + 1, "hide_emitters": False},
         "sensor": sensor(mi, doc, spp)}
    for i, s in enumerate(doc["shapes"]):
        sd = shape(mi, s, materials, tmp, f"shape{i}")
        if sd is not None:
            d[f"shape{i}"] = sd
    # Each instanced object once, as a shape group; instances refer to it.
    groups = set()
    for i, o in enumerate(doc["objects"]):
        shapes = [shape(mi, s, materials, tmp, f"object{i}-{j}") for j, s in enumerate(o["shapes"])]
        shapes = [s for s in shapes if s is not None]
        if shapes:
            d[f"object{i}"] = {"type": "shapegroup", **{f"shape{j}": s for j, s in enumerate(shapes)}}
            groups.add(i)
    for k, inst in enumerate(doc["instances"]):
        if inst["object"] in groups:
            d[f"instance{k}"] = {"type": "instance", "to_world": matrix(mi, inst["to_world"]),
                                 "shapegroup": {"type": "ref", "id": f"object{inst['object']}"}}
    for i, l in enumerate(doc["lights"]):
        d[f"light{i}"] = light(mi, l)
    return d


def write_exr(mi, path, image):
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".mitsuba-", suffix=".exr", dir=directory)
    os.close(fd)
    try:
        mi.Bitmap(image).write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def load_doc(path):
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except OSError as e:
        raise ExportError(f"cannot read: {e.strerror}")
    except json.JSONDecodeError as e:
        raise ExportError(f"{e.lineno}:{e.colno}: not JSON: {e.msg}")
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("version") != VERSION:
        raise ExportError(f"not a {FORMAT} version {VERSION} document (write it with `pbrt-sppm export --mitsuba`)")
    return doc


def main():
    ap = argparse.ArgumentParser(description="Render a pbrt-sppm Mitsuba export with Mitsuba 3's path tracer.")
    ap.add_argument("scene", help="JSON written by `pbrt-sppm export --mitsuba`")
    ap.add_argument("out", help="output EXR")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel (default 256)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant (default scalar_rgb)")
    args = ap.parse_args()
    where = args.scene
    try:
        doc = load_doc(args.scene)
        try:
            import mitsuba as mi
        except ImportError:
            where = "mitsuba"
            raise ExportError("the Python package `mitsuba` is not installed (python3 -m pip install mitsuba)")
        mi.set_variant(args.variant)
        for u in doc["unsupported"]:
            loc = u["where"] or doc["source"]
            print(f"{loc}: warning: {u['what']}: {u['why']}", file=sys.stderr)
        with tempfile.TemporaryDirectory() as tmp:
            scene = mi.load_dict(build(mi, doc, tmp, args.spp))
        check_camera(mi, scene, doc)
        start = time.perf_counter()
        image = mi.render(scene, spp=args.spp, seed=args.seed) * float(doc["film"]["scale"])
        seconds = time.perf_counter() - start
        where = args.out
        write_exr(mi, args.out, image)
    except (ExportError, KeyError, TypeError, ValueError, RuntimeError, OSError) as e:
        detail = f"missing key {e}" if isinstance(e, KeyError) else str(e)
        print(f"{where}: error: {detail}", file=sys.stderr)
        sys.exit(1)
    print(f"rendered {args.spp} spp with Mitsuba {mi.__version__} in {seconds:.2f} s -> {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
