#!/usr/bin/env python3
"""Writes src/spectrum/data.rs: the CIE tables pbrt-sppm's spectral code needs.

Source: the `colour-science` package (PyPI), which carries the CIE's published data.
Run once; the output is committed, so neither the build nor the tests need Python:

    python3 -m venv /tmp/cv && /tmp/cv/bin/pip install colour-science
    /tmp/cv/bin/python tools/spectral-data.py > src/spectrum/data.rs

- CIE 1931 2° colour matching functions, 1 nm, 360-830 nm (CIE 018:2019 data).
- CIE standard illuminant D65, 5 nm, 300-830 nm: the CIE table to 780 nm; beyond, the
  CIE daylight model at D65's chromaticity, scaled to meet the table at 780 nm (the
  colour-science table stops at 780 nm; the two agree there within 2e-5).
- pbrt-v4's named standard illuminants: A (Planck's law at 2856 K, as the CIE defines
  it, 300-830 nm), D50 (the CIE table to 780 nm, then the daylight model as for D65) and
  the fluorescent F1-F12 (CIE tables, 380-780 nm), each at 5 nm.
- The CIE daylight basis S0, S1, S2, 5 nm, 300-830 nm (pbrt-v4's `whitebalance` makes
  a daylight spectrum of them).
- The 18 chromatic patches of the Macbeth ColorChecker as measured by N. Ohta
  (reflectance, 5 nm, 380-780 nm), for the tests of the upsampling's round trip.
- ACES's white (about D60): the CIE daylight model at ACES's white point
  (0.32168, 0.33767), 5 nm, 300-830 nm.
"""
import warnings

warnings.filterwarnings("ignore")
import colour  # noqa: E402
import numpy as np  # noqa: E402


def literal(v):
    text = "%.10g" % v
    return text if any(c in text for c in ".en") else text + ".0"


def rust_array(name, values, doc):
    body = ",\n".join(
        "    " + ", ".join(literal(v) for v in values[i : i + 6]) for i in range(0, len(values), 6)
    )
    return f"/// {doc}\npub const {name}: [f64; {len(values)}] = [\n{body},\n];\n"


def main():
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    nm = np.arange(360, 831)
    xyz = cmfs[nm]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    xy65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    model = colour.sd_CIE_illuminant_D_series(xy65)
    five = np.arange(300, 831, 5)
    tail = model[five] * (d65[780] / model[780])
    d65_values = np.where(five <= 780, d65[np.minimum(five, 780)], tail)
    aces = colour.sd_CIE_illuminant_D_series(np.array([0.32168, 0.33767]))[five]
    out = ["//! CIE data, written by `tools/spectral-data.py` (see there for sources); do not edit.\n"]
    out.append("#![allow(clippy::excessive_precision, clippy::unreadable_literal, clippy::approx_constant)]\n")
    out.append(rust_array("CIE_X", xyz[:, 0], "CIE 1931 x̄(λ), λ = 360, 361, …, 830 nm."))
    out.append(rust_array("CIE_Y", xyz[:, 1], "CIE 1931 ȳ(λ), λ = 360, 361, …, 830 nm."))
    out.append(rust_array("CIE_Z", xyz[:, 2], "CIE 1931 z̄(λ), λ = 360, 361, …, 830 nm."))
    out.append(rust_array("ILLUM_D65", d65_values, "CIE illuminant D65, λ = 300, 305, …, 830 nm."))
    out.append(rust_array("ILLUM_ACES_D60", aces, "CIE daylight at ACES's white, λ = 300, 305, …, 830 nm."))
    from colour.colorimetry import SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as basis

    illum_a = colour.sd_CIE_standard_illuminant_A(colour.SpectralShape(300, 830, 5))[five]
    out.append(rust_array("ILLUM_A", illum_a, "CIE illuminant A, λ = 300, 305, …, 830 nm."))
    d50 = colour.SDS_ILLUMINANTS["D50"]
    xy50 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D50"]
    model50 = colour.sd_CIE_illuminant_D_series(xy50)
    tail50 = model50[five] * (d50[780] / model50[780])
    d50_values = np.where(five <= 780, d50[np.minimum(five, 780)], tail50)
    out.append(rust_array("ILLUM_D50", d50_values, "CIE illuminant D50, λ = 300, 305, …, 830 nm."))
    fl = np.arange(380, 781, 5)
    for i in range(1, 13):
        values = colour.SDS_ILLUMINANTS[f"FL{i}"][fl]
        out.append(rust_array(f"ILLUM_F{i}", values, f"CIE illuminant F{i}, λ = 380, 385, …, 780 nm."))

    for k in ["S0", "S1", "S2"]:
        out.append(rust_array(f"CIE_{k}", basis[k][five], f"CIE daylight basis {k}, λ = 300, 305, …, 830 nm."))
    cc = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    patches = list(cc.items())[:18]
    def patch(name, sd):
        values = [literal(v) for v in sd[np.arange(380, 781, 5)]]
        lines = ",\n".join("            " + ", ".join(values[i : i + 10]) for i in range(0, len(values), 10))
        return f'    (\n        "{name}",\n        [\n{lines},\n        ],\n    )'

    rows = ",\n".join(patch(name, sd) for name, sd in patches)
    out.append(
        "/// The ColorChecker's chromatic patches (N. Ohta): reflectance at 380, 385, …, 780 nm.\n"
        f"#[cfg(test)]\npub const COLORCHECKER_OHTA: [(&str, [f64; 81]); 18] = [\n{rows},\n];\n"
    )
    print("\n".join(out), end="")


main()
