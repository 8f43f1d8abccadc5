#!/usr/bin/env python3
"""Writes src/spectrum/metals.rs: the measured optical constants (η and k against
wavelength) of the metals pbrt-v4 names, `metal-Ag-eta` … `metal-TiO2-k`.

These are physical measurements, not pbrt's code: Ag, Al, Au and Cu as pbrt-v3 and
pbrt-v4 tabulate them (Palik's Handbook of Optical Constants of Solids, sampled every
0.1 eV), CuZn, MgO and TiO2 as they took them from refractiveindex.info (public
domain). pbrt-v4's images are made with exactly these samples, so we read them from
its source file (Apache-2.0), which must be given:

    python3 tools/metal-spectra.py PBRT_V4/src/pbrt/util/spectrum.cpp > src/spectrum/metals.rs
    cargo fmt

The output is committed, so neither the build nor the tests need pbrt or Python.
"""
import sys

from pbrt_source import literal, table

METALS = ["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"]


def main():
    text = open(sys.argv[1]).read()
    out = [
        "//! Measured η and k of the metals pbrt-v4 names, (λ nm, value) in increasing λ;",
        "//! written by `tools/metal-spectra.py` (see there for the sources); do not edit.",
        "",
        "#![allow(clippy::excessive_precision, clippy::unreadable_literal, clippy::approx_constant)]",
        "",
    ]
    names = []
    for metal in METALS:
        for part in ["eta", "k"]:
            pairs = table(text, f"{metal}_{part}")
            const = f"{metal.upper()}_{part.upper()}"
            names.append((f"metal-{metal}-{part}", const))
            body = "\n".join(
                "    " + " ".join(f"({literal(l)}, {literal(v)})," for l, v in pairs[i : i + 4])
                for i in range(0, len(pairs), 4)
            )
            out.append(f"/// `metal-{metal}-{part}`.")
            out.append(f"pub const {const}: [(f32, f32); {len(pairs)}] = [\n{body}\n];\n")
    out.append("/// Each name and its table.")
    out.append(f"pub const NAMED: [(&str, &[(f32, f32)]); {len(names)}] = [")
    out.extend(f'    ("{n}", &{c}),' for n, c in names)
    out.append("];")
    print("\n".join(out))


if __name__ == "__main__":
    main()
