"""Reading pbrt-v4's source tables, for the tools that take measured data from it
(metal-spectra.py, sensor-spectra.py)."""
import re
import sys


def table(text, name):
    """The (x, y) pairs of `const Float name[] = {x0, y0, x1, y1, ...};`, x increasing."""
    m = re.search(r"const Float %s\[\] = \{(.*?)\};" % re.escape(name), text, re.S)
    if not m:
        sys.exit(f"{name}: not found")
    values = [float(v) for v in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?", m.group(1))]
    if len(values) % 2:
        sys.exit(f"{name}: an odd number of values")
    pairs = list(zip(values[0::2], values[1::2]))
    if any(b[0] <= a[0] for a, b in zip(pairs, pairs[1:])):
        sys.exit(f"{name}: wavelengths do not increase")
    return pairs


def literal(v):
    """A Rust float literal of `v` to 9 significant digits."""
    text = "%.9g" % v
    return text if any(c in text for c in ".e") else text + ".0"
