#!/usr/bin/env python3
"""Writes src/spectrum/sensors.rs: what pbrt-v4's named camera sensors need.

- The measured red, green and blue sensitivities of the 17 cameras pbrt-v4 names
  (`"string sensor" "nikon_d850"` ...), 380-720 nm every 10 nm. They are Weta Digital's
  PhysLight measurements (Anders Langlands and Luca Fascione, Copyright (c) 2020 Weta
  Digital, Ltd., Apache-2.0), as pbrt-v4 carries them; pbrt-v4's images are made with
  exactly these samples, so we read them from its source file (Apache-2.0), which must
  be given.
- The 24 ColorChecker patches (BabelColor's average of measured charts, 380-730 nm
  every 10 nm) that pbrt-v4 fits each camera's matrix to, taken from the
  `colour-science` package (PyPI), which carries the same data.

    python3 -m venv /tmp/cv && /tmp/cv/bin/pip install colour-science
    /tmp/cv/bin/python tools/sensor-spectra.py PBRT_V4/src/pbrt/util/spectrum.cpp \
        > src/spectrum/sensors.rs

The output is laid out by this tool (rustfmt skips it), six values to a line.

The output is committed, so neither the build nor the tests need pbrt or Python.
"""
import sys
import warnings

from pbrt_source import literal, table

warnings.filterwarnings("ignore")
import colour  # noqa: E402

CAMERAS = [
    "canon_eos_100d",
    "canon_eos_1dx_mkii",
    "canon_eos_200d",
    "canon_eos_200d_mkii",
    "canon_eos_5d",
    "canon_eos_5d_mkii",
    "canon_eos_5d_mkiii",
    "canon_eos_5d_mkiv",
    "canon_eos_5ds",
    "canon_eos_m",
    "hasselblad_l1d_20c",
    "nikon_d810",
    "nikon_d850",
    "sony_ilce_6400",
    "sony_ilce_7m3",
    "sony_ilce_7rm3",
    "sony_ilce_9",
]


def curve(text, name):
    """A camera curve's values, checked to be sampled every 10 nm from 380 to 720 nm."""
    pairs = table(text, name)
    if [l for l, _ in pairs] != [380.0 + 10.0 * i for i in range(35)]:
        sys.exit(f"{name}: not sampled every 10 nm from 380 to 720 nm")
    return [v for _, v in pairs]


def rows(values, indent="        "):
    return "\n".join(indent + " ".join(literal(v) + "," for v in values[i : i + 6]) for i in range(0, len(values), 6))


def cameras(text):
    out = [
        "/// Each camera's red, green and blue sensitivity at 380, 390, …, 720 nm.",
        "///",
        "/// PhysLight measurements contributed to pbrt-v4 by Anders Langlands and Luca",
        "/// Fascione. Copyright (c) 2020, Weta Digital, Ltd. SPDX-License-Identifier: Apache-2.0",
        f"pub const CAMERAS: [(&str, [[f32; 35]; 3]); {len(CAMERAS)}] = [",
    ]
    for camera in CAMERAS:
        out.append(f'    ("{camera}", [')
        for channel in "rgb":
            out.append(f"        [\n{rows(curve(text, f'{camera}_{channel}'), '            ')}\n        ],")
        out.append("    ]),")
    out.append("];\n")
    return out


def swatches():
    charts = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    out = [
        "/// The 24 ColorChecker patches, BabelColor's average (Danny Pascale), reflectance at",
        "/// 380, 390, …, 730 nm, from `colour-science`: what pbrt-v4 fits a camera's matrix to.",
        f"pub const SWATCHES: [[f32; 36]; {len(charts)}] = [",
    ]
    for name, sd in charts.items():
        if list(sd.wavelengths) != [380.0 + 10.0 * i for i in range(36)]:
            sys.exit(f"{name}: not sampled every 10 nm from 380 to 730 nm")
        out.append(f"    // {name}\n    [\n{rows(list(sd.values))}\n    ],")
    out.append("];")
    return out


def main():
    text = open(sys.argv[1]).read()
    out = [
        "//! pbrt-v4's named camera sensors: their measured curves and the chart their",
        "//! matrices are fitted to; written by `tools/sensor-spectra.py` (see there for the",
        "//! sources); do not edit.",
        "",
        "#![allow(clippy::excessive_precision, clippy::unreadable_literal, clippy::approx_constant)]",
        "",
    ]
    print("\n".join(out + cameras(text) + swatches()))


if __name__ == "__main__":
    main()
