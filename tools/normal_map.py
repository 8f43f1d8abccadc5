#!/usr/bin/env python3
"""Writes pbrt-scenes/verify/textures/domes-normal.png: a 64x64 tangent-space normal
map of a 4x4 grid of domes (RGB = (n + 1) / 2, +z up), for v4-normalmap.pbrt.

    python3 tools/normal_map.py pbrt-scenes/verify/textures/domes-normal.png
"""
import math, struct, sys, zlib

N, CELLS = 64, 4
rows = []
for y in range(N):
    row = bytearray()
    for x in range(N):
        # Position within the cell, in [-1, 1]; a dome of radius .8.
        u = ((x + 0.5) * CELLS / N) % 1 * 2 - 1
        v = ((y + 0.5) * CELLS / N) % 1 * 2 - 1
        r2 = (u * u + v * v) / 0.64
        if r2 < 1:
            h = math.sqrt(1 - r2)
            n = (u / 0.8, -v / 0.8, h)  # image rows run down, v up
        else:
            n = (0.0, 0.0, 1.0)
        length = math.sqrt(sum(c * c for c in n))
        row += bytes(round((c / length + 1) / 2 * 255) for c in n)
    rows.append(bytes([0]) + bytes(row))

def chunk(tag, data):
    return struct.pack('>I', len(data)) + tag + data + struct.pack('>I', zlib.crc32(tag + data))

png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', N, N, 8, 2, 0, 0, 0))
png += chunk(b'IDAT', zlib.compress(b''.join(rows))) + chunk(b'IEND', b'')
open(sys.argv[1], 'wb').write(png)
