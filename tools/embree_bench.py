#!/usr/bin/env python3
"""Trace the rays of `pbrt-bench rays --dump` with Embree (PyPI package `embreex`), so
our BVH can be compared with Embree on the same machine, mesh and rays.

    python3 -m venv /tmp/embree-venv && /tmp/embree-venv/bin/pip install embreex numpy
    cargo run --release --bin pbrt-bench -- rays --dump
    /tmp/embree-venv/bin/python tools/embree_bench.py [target/bench-data] [--runs 5]

embreex traces one ray at a time (rtcIntersect1/rtcOccluded1) on one thread, so compare
with pbrt-bench's 1-thread rows.
"""
import statistics
import sys
import time

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    runs = int(sys.argv[sys.argv.index("--runs") + 1]) if "--runs" in sys.argv else 5
    if "--runs" in sys.argv:
        args = [a for a in args if a != str(runs)]
    d = args[0] if args else "target/bench-data"
    v = np.fromfile(f"{d}/vertices.f32", dtype="<f4").reshape(-1, 3)
    f = np.fromfile(f"{d}/indices.u32", dtype="<u4").astype(np.int32).reshape(-1, 3)
    builds = []
    for _ in range(runs):
        t = time.perf_counter()
        scene = rtcs.EmbreeScene()
        TriangleMesh(scene, v, f)
        scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commit
        builds.append(time.perf_counter() - t)
    print(f"embree: {len(f)} triangles, build (median of {runs}): {statistics.median(builds):.3f} s")
    print(f"{'rays':<22} {'closest Mray/s':>14} {'any-hit Mray/s':>14} {'hits':>10}")
    for name, key in [("coherent (camera)", "camera"), ("incoherent (random)", "random")]:
        o = np.fromfile(f"{d}/{key}_o.f32", dtype="<f4").reshape(-1, 3)
        dirs = np.fromfile(f"{d}/{key}_d.f32", dtype="<f4").reshape(-1, 3)
        out = {}
        for query in ["INTERSECT", "OCCLUDED"]:
            times = []
            for _ in range(runs):
                t = time.perf_counter()
                res = scene.run(o, dirs, query=query)
                times.append(time.perf_counter() - t)
            out[query] = (len(o) / statistics.median(times) / 1e6, int(np.count_nonzero(np.asarray(res) != -1)))
        print(f"{name:<22} {out['INTERSECT'][0]:>14.2f} {out['OCCLUDED'][0]:>14.2f} {out['INTERSECT'][1]:>10}")


if __name__ == "__main__":
    main()
