#!/usr/bin/env python3
"""Writes pbrt-v4 `measured` BSDF files (the RGL "tensor_file" format) of our own design.

    python3 tools/make_measured_bsdf.py [DIR]   # default pbrt-scenes/verify/bsdfs

Standard library only. Two files, both a rough metal-like reflector with a spectral
Fresnel term, tabulated the way the RGL database stores its measurements (Dupuy and
Jakob 2018) and pbrt-v4's `MeasuredBxDF` reads them:

- `rosegold.bsdf`, isotropic (one `phi_i`): GGX alpha 0.3, reflectance at normal
  incidence rising from 0.25 in the blue to 0.9 in the red;
- `anodized.bsdf`, anisotropic (`phi_i` over the full circle): GGX alpha 0.08 along
  x and 0.4 along y, a violet-blue reflectance.

The BRDF is f = S D(wm) / (4 sigma(wo) cos theta_i): `ndf` holds D on a grid over
(sqrt(2 theta / pi), phi / 2pi + 1/2), `sigma` the projected area of the microsurface
seen from wo, `vndf` the visible normals' density in the same coordinates (times the
map's Jacobian) per incident (phi_i, theta_i), and `spectra` S = F(wo . wm) G2 / G1(wo)
per wavelength on a grid over the square that `vndf`'s warp maps to normals, which this
script places by the same warp pbrt-v4's `PiecewiseLinear2D` samples with. `luminance`
is S weighted by an analytic fit of CIE y-bar, which pbrt samples by.
"""
import math
import os
import struct
import sys

PI = math.pi
UINT8, FLOAT32 = 1, 10
N_NDF = 32  # ndf and sigma: theta nodes (phi nodes: 2 isotropic, 33 otherwise)
# vndf, luminance and spectra: nodes per side, and the incident elevations, per file.
FINE = (16, [math.radians(d) for d in (0, 15, 30, 45, 60, 70, 80, 88)])
COARSE = (12, [math.radians(d) for d in (0, 20, 40, 60, 75, 88)])


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def u2theta(u):
    return u * u * PI / 2


def u2phi(u):
    return (2 * u - 1) * PI


def direction(theta, phi):
    s = math.sin(theta)
    return (s * math.cos(phi), s * math.sin(phi), math.cos(theta))


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


class Ggx:
    def __init__(self, ax, ay, f0):
        self.ax, self.ay, self.f0 = ax, ay, f0

    def d(self, m):
        if m[2] <= 0:
            return 0.0
        e = (m[0] / self.ax) ** 2 + (m[1] / self.ay) ** 2 + m[2] ** 2
        return 1 / (PI * self.ax * self.ay * e * e)

    def lam(self, w):
        if w[2] >= 1:
            return 0.0
        t2 = (self.ax * w[0]) ** 2 + (self.ay * w[1]) ** 2
        return (-1 + math.sqrt(1 + t2 / (w[2] * w[2]))) / 2 if w[2] > 0 else float("inf")

    def sigma(self, w):
        """Projected area of the microsurface: the integral of D(m) max(0, w . m)."""
        t2 = (self.ax * w[0]) ** 2 + (self.ay * w[1]) ** 2
        return (w[2] + math.sqrt(w[2] * w[2] + t2)) / 2

    def s(self, wo, wi, m, lam):
        """S = F G2 / G1(wo) at wavelength lam (nm)."""
        c = max(0.0, dot(wo, m))
        f0 = self.f0(lam)
        fresnel = f0 + (1 - f0) * (1 - c) ** 5
        g2 = 1 / (1 + self.lam(wo) + self.lam(wi))
        g1 = 1 / (1 + self.lam(wo))
        return fresnel * g2 / g1


def rosegold(lam):
    return 0.25 + 0.65 / (1 + math.exp(-(lam - 580) / 25))


def anodized(lam):
    return 0.12 + 0.6 * math.exp(-(((lam - 440) / 55) ** 2))


def ybar(lam):
    """CIE 1931 y-bar, the multi-lobe fit of Wyman, Sloan and Shirley (2013)."""
    def g(x, mu, s1, s2):
        t = (x - mu) / (s1 if x < mu else s2)
        return math.exp(-0.5 * t * t)
    return 0.821 * g(lam, 568.8, 46.9, 40.5) + 0.286 * g(lam, 530.9, 16.3, 31.1)


class Warp:
    """pbrt-v4's PiecewiseLinear2D<0> sampling of one slice (float64 here)."""

    def __init__(self, data, nx, ny):
        self.nx, self.ny = nx, ny
        cond = [0.0] * (nx * ny)
        for y in range(ny):
            s = 0.0
            for x in range(nx - 1):
                i = y * nx + x
                s += 0.5 * (data[i] + data[i + 1])
                cond[i + 1] = f32(s)
        marg, s = [0.0] * ny, 0.0
        for y in range(ny - 1):
            s += 0.5 * (cond[(y + 1) * nx - 1] + cond[(y + 2) * nx - 1])
            marg[y + 1] = f32(s)
        norm = 1 / marg[-1]
        self.cond = [c * norm for c in cond]
        self.marg = [m * norm for m in marg]
        self.data = [d * norm for d in data]

    @staticmethod
    def interval(n, pred):
        lo = 0
        for i in range(n):
            if pred(i):
                lo = i
        return min(max(lo, 0), n - 2)

    @staticmethod
    def solve(v0, v1, u):
        if abs(v0 - v1) < 1e-4 * (v0 + v1):
            return 2 * u / (v0 + v1)
        return (v0 - math.sqrt(max(0.0, v0 * v0 - 2 * u * (v0 - v1)))) / (v0 - v1)

    def sample(self, ux, uy):
        nx = self.nx
        row = self.interval(self.ny, lambda i: self.marg[i] < uy)
        uy -= self.marg[row]
        o = row * nx
        r0, r1 = self.cond[o + nx - 1], self.cond[o + 2 * nx - 1]
        ty = self.solve(r0, r1, uy)
        ux *= (1 - ty) * r0 + ty * r1
        conditional = lambda i: (1 - ty) * self.cond[o + i] + ty * self.cond[o + nx + i]
        col = self.interval(nx, lambda i: conditional(i) < ux)
        ux -= conditional(col)
        o += col
        v = self.data
        c0 = (1 - ty) * v[o] + ty * v[o + nx]
        c1 = (1 - ty) * v[o + 1] + ty * v[o + nx + 1]
        tx = self.solve(c0, c1, ux)
        return (col + tx) / (nx - 1), (row + ty) / (self.ny - 1)


def vndf_slice(brdf, wo, phi_o, isotropic, n):
    sig, out = brdf.sigma(wo), []
    for y in range(n):
        for x in range(n):
            u = (x / (n - 1), y / (n - 1))
            theta, phi = u2theta(u[0]), u2phi(u[1]) + (phi_o if isotropic else 0)
            m = direction(theta, phi)
            jac = 2 * PI * PI * u[0] * math.sin(theta)
            out.append(f32(brdf.d(m) * max(0.0, dot(wo, m)) / sig * jac))
    return out


def square_slices(brdf, wo, phi_o, isotropic, lams, n):
    """(vndf, luminance, spectra per wavelength) for the incident direction wo."""
    vndf = vndf_slice(brdf, wo, phi_o, isotropic, n)
    warp = Warp(vndf, n, n)
    spectra = [[0.0] * (n * n) for _ in lams]
    lum = [0.0] * (n * n)
    for y in range(n):
        for x in range(n):
            ux, uy = warp.sample(min(max(x / (n - 1), 1e-7), 1 - 1e-7), min(max(y / (n - 1), 1e-7), 1 - 1e-7))
            phi = u2phi(uy) + (phi_o if isotropic else 0)
            m = direction(u2theta(ux), phi)
            c = dot(wo, m)
            wi = tuple(2 * c * m[k] - wo[k] for k in range(3))
            if wi[2] <= 0:
                continue
            values = [brdf.s(wo, wi, m, lam) for lam in lams]
            for k, v in enumerate(values):
                spectra[k][y * n + x] = f32(v)
            lum[y * n + x] = f32(sum(v * ybar(lam) for v, lam in zip(values, lams)) / sum(ybar(l) for l in lams))
    return vndf, lum, spectra


def tables(brdf, isotropic, lams, grid):
    n, thetas = grid
    phis_i = [0.0] if isotropic else [u2phi(k / 8) for k in range(9)]
    n_phi = 2 if isotropic else 33
    ndf, sigma = [], []
    for y in range(n_phi):
        for x in range(N_NDF):
            theta, phi = u2theta(x / (N_NDF - 1)), u2phi(y / (n_phi - 1))
            w = direction(theta, phi)
            ndf.append(f32(brdf.d(w)))
            sigma.append(f32(brdf.sigma(w)))
    vndf, lum, spectra = [], [], []
    for phi_o in phis_i:
        for theta_o in thetas:
            v, l, s = square_slices(brdf, direction(theta_o, phi_o), phi_o, isotropic, lams, n)
            vndf += v
            lum += l
            for k in s:
                spectra += k
    nl = len(lams)
    return [
        ("description", UINT8, [0], None),
        ("jacobian", UINT8, [1], bytes([1])),
        ("theta_i", FLOAT32, [len(thetas)], thetas),
        ("phi_i", FLOAT32, [len(phis_i)], phis_i),
        ("wavelengths", FLOAT32, [nl], lams),
        ("ndf", FLOAT32, [n_phi, N_NDF], ndf),
        ("sigma", FLOAT32, [n_phi, N_NDF], sigma),
        ("vndf", FLOAT32, [len(phis_i), len(thetas), n, n], vndf),
        ("luminance", FLOAT32, [len(phis_i), len(thetas), n, n], lum),
        ("spectra", FLOAT32, [len(phis_i), len(thetas), nl, n, n], spectra),
    ]


def tensor_file(fields, description):
    """The "tensor_file" container: header, field table, then each field's data."""
    blobs = []
    for name, dtype, shape, data in fields:
        if name == "description":
            blob, shape = description.encode(), [len(description)]
        elif dtype == UINT8:
            blob = data
        else:
            blob = struct.pack("<%df" % len(data), *data)
        blobs.append((name, dtype, shape, blob))
    head = len(b"tensor_file\0") + 2 + 4
    head += sum(2 + len(n) + 2 + 1 + 8 + 8 * len(s) for n, _, s, _ in blobs)
    table, body, offset = b"", b"", head
    for name, dtype, shape, blob in blobs:
        offset += (-offset) % 8
        body += b"\0" * ((offset - head) - len(body))
        table += struct.pack("<H", len(name)) + name.encode() + struct.pack("<HBQ", len(shape), dtype, offset)
        table += b"".join(struct.pack("<Q", s) for s in shape)
        body += blob
        offset += len(blob)
    return b"tensor_file\0" + bytes([1, 0]) + struct.pack("<I", len(blobs)) + table + body


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "pbrt-scenes/verify/bsdfs"
    os.makedirs(out, exist_ok=True)
    files = [
        ("rosegold.bsdf", Ggx(0.3, 0.3, rosegold), True, [360 + 47 * k for k in range(11)], FINE,
         "pbrt-sppm test: isotropic GGX 0.3, rose-gold Fresnel"),
        ("anodized.bsdf", Ggx(0.08, 0.4, anodized), False, [360 + 117.5 * k for k in range(5)], COARSE,
         "pbrt-sppm test: anisotropic GGX 0.08 x 0.4, violet-blue Fresnel"),
    ]
    for name, brdf, isotropic, lams, grid, description in files:
        data = tensor_file(tables(brdf, isotropic, [float(l) for l in lams], grid), description)
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
