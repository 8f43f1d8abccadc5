#!/usr/bin/env python3
"""Writes tests/data/nanovdb/puff.nvdb: the NanoVDB test grid of the `nanovdb` medium.

A puff of smoke as two float fog-volume grids in one file: "density", a soft ball
(radius 14 voxels, squashed in y, rippled) with a constant slab of 0.3 under it that
OpenVDB prunes into tiles, and "temperature", 1500-2900 K over the ball's core. Voxels
are 0.05 wide and index (0, 0, 0) sits at world (0.1, 0.9, 0). The grids are written by
OpenVDB's Python module and converted by NanoVDB's own tool, ZIP-compressed:

    apt install python3-openvdb libnanovdb-tools
    /usr/bin/python3 tools/make_nanovdb_puff.py [out.nvdb] [--uncompressed]

`tests/it/nanovdb.rs` checks voxel values against `density_at` and `temperature_at`
below (the same formulas, written again in Rust).
"""
import math
import os
import subprocess
import sys
import tempfile

import pyopenvdb as vdb

R = 14.0


def density_at(i, j, k):
    r = math.sqrt(i * i + (j * 1.2) ** 2 + k * k)
    if r >= R:
        return None
    return (1 - r / R) ** 1.5 * (1.0 + 0.5 * math.sin(0.7 * i) * math.cos(0.5 * k))


def temperature_at(i, j, k):
    r = math.sqrt(i * i + (j * 1.2) ** 2 + k * k)
    return 1500.0 + 200.0 * (7 - r) if r < 7 else None


def grids():
    density, temp = vdb.FloatGrid(0.0), vdb.FloatGrid(0.0)
    for g, name in ((density, "density"), (temp, "temperature")):
        g.name, g.gridClass = name, vdb.GridClass.FOG_VOLUME
    acc, tacc = density.getAccessor(), temp.getAccessor()
    for i in range(-16, 17):
        for j in range(-16, 17):
            for k in range(-16, 17):
                d, t = density_at(i, j, k), temperature_at(i, j, k)
                if d is not None:
                    acc.setValueOn((i, j, k), d)
                if t is not None:
                    tacc.setValueOn((i, j, k), t)
    # A slab of 16 x 8 x 16 voxels of 0.3 under the ball: whole leaves, pruned to tiles.
    for i in range(16, 32):
        for j in range(-24, -16):
            for k in range(0, 16):
                acc.setValueOn((i, j, k), 0.3)
    density.prune()
    xf = vdb.createLinearTransform(voxelSize=0.05)
    xf.translate((0.1, 0.9, 0.0))
    density.transform = xf
    temp.transform = xf
    return [density, temp]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    out = args[0] if args else os.path.join(os.path.dirname(__file__), "..", "tests", "data", "nanovdb", "puff.nvdb")
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "puff.vdb")
        vdb.write(src, grids=grids())
        zip_flag = [] if "--uncompressed" in sys.argv else ["-z"]
        subprocess.run(["nanovdb_convert", "-f", *zip_flag, src, out], check=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
