#!/usr/bin/env python3
"""Writes a pbrt-v3 Fourier BSDF file (`SCATFUN` version 1) of our own design.

    python3 tools/make_fourier_bsdf.py [OUT]   # default pbrt-scenes/verify/bsdfs/glazed.bsdf

Standard library only. The BSDF is an isotropic "glazed" surface: a brown Lambertian
base with a Phong-like gloss around the mirror direction, and a faint bluish
transmission, diffuse plus a lobe around the straight-through direction, relative index
1.2. For each pair of zenith cosines (mu_i, mu_o) on 25 nodes over [-1, 1] (denser near
+-1) the file stores the Fourier coefficients in the azimuth difference phi of
|mu_i| f(mu_i, mu_o, phi), for luminance, red and blue (pbrt-v3 recovers green), up to
48 terms, trimmed where they stop mattering; then per mu_o row the running integral
over mu_i of the first luminance coefficient (pbrt's Catmull-Rom rule), which pbrt-v3
samples mu_i by.
"""
import math
import os
import struct
import sys

N_MU = 25
M_MAX = 48
N_PHI = 256
ETA = 1.2
KD = (0.40, 0.22, 0.08)
KS, N_S = (0.35, 0.35, 0.35), 40.0
KT = (0.04, 0.10, 0.18)
KTS, N_T = (0.06, 0.12, 0.20), 12.0
LUM = (0.212671, 0.715160, 0.072169)


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def bsdf(mu_i, mu_o, cos_phi):
    """f(mu_i, mu_o, phi) per RGB channel; mu_i is the cosine of -wi, as in pbrt."""
    s = math.sqrt(max(0.0, 1 - mu_i * mu_i)) * math.sqrt(max(0.0, 1 - mu_o * mu_o))
    if mu_i * mu_o < 0:  # reflection
        c = max(0.0, s * cos_phi + abs(mu_i * mu_o))
        lobe = (N_S + 2) / (2 * math.pi) * c**N_S
        return [kd / math.pi + ks * lobe for kd, ks in zip(KD, KS)]
    c = max(0.0, s * cos_phi + mu_i * mu_o)  # transmission: around straight through
    lobe = (N_T + 2) / (2 * math.pi) * c**N_T
    return [kt / math.pi + ks * lobe for kt, ks in zip(KT, KTS)]


def coefficients(mu_i, mu_o, cosines):
    """Fourier coefficients of |mu_i| f over phi in [0, pi], for luminance, red, blue."""
    phis = [math.pi * (j + 0.5) / N_PHI for j in range(N_PHI)]
    ys = [[abs(mu_i) * v for v in bsdf(mu_i, mu_o, math.cos(p))] for p in phis]
    series = [[sum(LUM[c] * y[c] for c in range(3)) for y in ys], [y[0] for y in ys], [y[2] for y in ys]]
    out = []
    for values in series:
        a = [sum(v * cs for v, cs in zip(values, cosines[k])) * (1 if k == 0 else 2) / N_PHI for k in range(M_MAX)]
        out.append(a)
    peak = max(abs(x) for a in out for x in a)
    m = max([k + 1 for a in out for k, x in enumerate(a) if abs(x) > 1e-5 * peak] or [1])
    return [[f32(x) for x in a[:m]] for a in out]


def integrate_catmull_rom(x, values):
    """pbrt's IntegrateCatmullRom: the running integral of the spline through values."""
    cdf, total = [0.0], 0.0
    n = len(x)
    for i in range(n - 1):
        x0, x1, f0, f1 = x[i], x[i + 1], values[i], values[i + 1]
        width = x1 - x0
        d0 = width * (f1 - values[i - 1]) / (x1 - x[i - 1]) if i > 0 else f1 - f0
        d1 = width * (values[i + 2] - f0) / (x[i + 2] - x0) if i + 2 < n else f1 - f0
        total += ((d0 - d1) * (1 / 12) + (f0 + f1) * 0.5) * width
        cdf.append(total)
    return cdf


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "pbrt-scenes/verify/bsdfs/glazed.bsdf"
    mu = [f32(-math.cos(math.pi * i / (N_MU - 1))) for i in range(N_MU)]
    mu[N_MU // 2] = 0.0
    cosines = [[math.cos(k * math.pi * (j + 0.5) / N_PHI) for j in range(N_PHI)] for k in range(M_MAX)]
    coeffs, table, a0 = [], [], []
    for o in range(N_MU):
        for i in range(N_MU):
            c = coefficients(mu[i], mu[o], cosines)
            m = len(c[0])
            table.append((len(coeffs), m))
            for a in c:
                coeffs += a
            a0.append(c[0][0])
    cdf = []
    for o in range(N_MU):
        cdf += [f32(x) for x in integrate_catmull_rom(mu, a0[o * N_MU:(o + 1) * N_MU])]
    m_max = max(m for _, m in table)
    header = b"SCATFUN\x01" + struct.pack("<9i", 1, N_MU, len(coeffs), m_max, 3, 1, 0, 0, 0)
    header += struct.pack("<5f", ETA, 0, 0, 0, 0)
    assert len(header) == 64
    body = struct.pack("<%df" % N_MU, *mu) + struct.pack("<%df" % len(cdf), *cdf)
    body += b"".join(struct.pack("<2i", off, m) for off, m in table)
    body += struct.pack("<%df" % len(coeffs), *coeffs)
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    with open(out, "wb") as f:
        f.write(header + body)


if __name__ == "__main__":
    main()
