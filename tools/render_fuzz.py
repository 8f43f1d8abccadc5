#!/usr/bin/env python3
"""Mutates the small scenes of pbrt-scenes/ and renders each mutant briefly, looking for
what the byte fuzzers (tools/fuzz) cannot reach: renders that hang, crash or write
non-finite pixels.

    cargo build --release
    python3 tools/render_fuzz.py SEED COUNT [--timeout 30]

Each mutant is a scene file under 20 KB with one to three mutations: a number replaced
by an extreme one, a token or line deleted, a line duplicated or swapped, a parameter's
type or a string value swapped, an array shortened, or one of the hostile statements
below inserted. It renders for 2 passes of 2,000 photons with SPPM, vcm, bdpt or direct
(and adaptive photons, guiding, point gathering). Flagged, and copied with its stderr
to target/render-fuzz/found/: an exit status other than 0 and 1, a panic, an error
without a file:line:col location, a timeout, a NaN or infinite pixel.
Standard library only.
"""
import argparse
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target/release/pbrt-sppm")
IMGTOOL = os.path.join(ROOT, "target/release/pbrt-imgtool")
FOUND = os.path.join(ROOT, "target/render-fuzz/found")

TYPES = ["float", "integer", "rgb", "color", "spectrum", "string", "bool", "point3", "point", "normal",
         "texture", "point2", "vector3", "blackbody"]
NUMBERS = ["0", "-1", "1e30", "-1e30", "2147483647", "-2147483648", "1e-30", "0.5", "1e9", "-0.0", "3", "65536",
           "1e38", "-7"]
STRINGS = ['"sphere"', '"trianglemesh"', '"matte"', '"glass"', '"conductor"', '"dielectric"', '"mix"', '"imagemap"',
           '"infinite"', '"spot"', '"homogeneous"', '"uniformgrid"', '"bilinearmesh"', '"loopsubdiv"', '"curve"',
           '"plymesh"', '"realistic"', '"spectral"', '"hair"', '"measured"', '"interface"', '"coateddiffuse"',
           '"bdpt"', '"volpath"', '"gbuffer"', '"gaussian"', '"mitchell"', '""', '"nonexistent"',
           '"../../../etc/passwd"']
STATEMENTS = [
    'Scale 0 0 0', 'Scale 1e30 1 1', 'Scale -1 1 1', 'Transform [0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0]',
    'ReverseOrientation', 'AttributeEnd', 'AttributeBegin', 'TransformBegin', 'ObjectEnd', 'ObjectBegin "x"',
    'ObjectInstance "x"', 'CoordSysTransform "camera"', 'ActiveTransform StartTime', 'TransformTimes 0 1e30',
    'Translate 1e20 0 0', 'Rotate 90 0 0 0', 'MediumInterface "a" "b"', 'Material "none"', 'Material ""',
    'Shape "sphere" "float radius" 1e-30', 'Shape "sphere" "float radius" -1',
    'LightSource "point" "rgb I" [1e30 1e30 1e30]', 'AreaLightSource "diffuse" "rgb L" [1 1 1]',
    'Shape "disk" "float radius" 0', 'Shape "cylinder" "float zmin" 1 "float zmax" 1',
    'Shape "trianglemesh" "point3 P" [0 0 0 0 0 0 0 0 0] "integer indices" [0 1 2]',
    'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 5]',
    'LightSource "infinite" "rgb L" [1 1 1]', 'LightSource "distant" "rgb L" [1e30 1 1]',
    'Attribute "shape" "float radius" 2',
    'MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [1e9 1e9 1e9] "rgb sigma_s" [0 0 0]',
    'MediumInterface "m" ""',
    'Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0] "integer indices" [0 1 2 3]',
    'Shape "curve" "point3 P" [0 0 0 1 1 1 2 0 0 3 1 1] "float width" 0',
    'Texture "t" "spectrum" "checkerboard" "float uscale" 1e30',
    'Shape "loopsubdiv" "integer levels" 30 "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]',
    'Shape "sphere" "float radius" 1 "float phimax" 0', 'Shape "paraboloid" "float radius" 0',
    'Shape "hyperboloid" "point3 p1" [0 0 0] "point3 p2" [0 0 0]',
    'LightSource "infinite" "rgb L" [1 1 1] "point3 portal" [0 0 0  0 1 0  1 1 0  1 0 0]',
    'LightSource "infinite" "point3 portal" [0 0 0  0 1e-30 0  1e-30 1e-30 0  1e-30 0 0]',
    'LightSource "infinite" "point3 portal" [0 0 0  0 1e30 0  1e30 1e30 0  1e30 0 0]',
    'LightSource "infinite" "point3 portal" [0 0 0  0 1 0  2 1 0  1 0 0]',
]
INTEGRATORS = [["sppm"], ["vcm"], ["bdpt"], ["direct"], ["sppm", "--photon-sampling", "adaptive"],
               ["vcm", "--guiding", "both"], ["sppm", "--volume-gather", "points"]]
TOKEN = re.compile(r'"[^"\n]*"|\[|\]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[A-Za-z_]+')


def mutate(text, rng):
    """One mutation of the scene text."""
    kind = rng.choice(["number"] * 3 + ["statement"] * 3 + ["dup", "del", "swap", "type", "string", "truncate",
                                                             "token"])
    tokens = list(TOKEN.finditer(text))
    lines = text.split("\n")
    pick = lambda ms: rng.choice(ms) if ms else None
    if kind == "number":
        m = pick([m for m in tokens if re.match(r"[-+.\d]", m.group())])
        return text if m is None else text[:m.start()] + rng.choice(NUMBERS) + text[m.end():]
    if kind == "token":
        m = pick(tokens)
        return text if m is None else text[:m.start()] + text[m.end():]
    if kind in ("dup", "del", "swap"):
        i = rng.randrange(len(lines))
        if kind == "dup":
            lines.insert(i, lines[i])
        elif kind == "del":
            del lines[i]
        else:
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        return "\n".join(lines)
    if kind == "type":
        m = pick([m for m in tokens if m.group().startswith('"') and m.group()[1:].split(" ")[0] in TYPES
                  and " " in m.group()])
        if m is None:
            return text
        name = m.group()[1:-1].split(" ", 1)[1]
        return text[:m.start()] + '"%s %s"' % (rng.choice(TYPES), name) + text[m.end():]
    if kind == "string":
        m = pick([m for m in tokens if m.group().startswith('"') and " " not in m.group()])
        return text if m is None else text[:m.start()] + rng.choice(STRINGS) + text[m.end():]
    if kind == "truncate":
        m = pick([m for m in tokens if m.group() == "]"])
        if m is None:
            return text
        before = text[:m.start()].rstrip()
        cut = max(before.rfind(" "), before.rfind("["))
        return before[:cut + 1] + " " + text[m.start():]
    lines.insert(rng.randrange(len(lines) + 1), rng.choice(STATEMENTS))
    return "\n".join(lines)


def mirror(scene_dirs, work):
    """A folder per scene folder, its entries linked, so that mutants find their includes."""
    for d in scene_dirs:
        m = os.path.join(work, os.path.basename(d))
        os.makedirs(m, exist_ok=True)
        for e in os.listdir(d):
            os.symlink(os.path.join(d, e), os.path.join(m, e))


def verdict(cmd, out, timeout):
    """What is wrong with the render (or None), its stderr and how it ended."""
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", "", "timeout"
    ended = "rendered" if r.returncode == 0 else "located error"
    if r.returncode not in (0, 1):
        return "status-%d" % r.returncode, r.stderr, ended
    if "panicked" in r.stderr:
        return "panic", r.stderr, ended
    if r.returncode == 1 and not re.match(r"[^:\n]+:\d+:\d+: error:", r.stderr):
        return "unlocated", r.stderr, ended
    if r.returncode == 0:
        info = subprocess.run([IMGTOOL, "info", out], capture_output=True, text=True).stdout
        if re.search(r"NaN|inf", info):
            return "non-finite", r.stderr, ended
    return None, r.stderr, ended


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("seed", type=int)
    ap.add_argument("count", type=int)
    ap.add_argument("--timeout", type=float, default=30.0)
    a = ap.parse_args()
    if not os.path.exists(BIN) or not os.path.exists(IMGTOOL):
        sys.exit("build first: cargo build --release")
    rng = random.Random(a.seed)
    base = os.path.join(ROOT, "pbrt-scenes")
    files = [os.path.join(base, d, f) for d in sorted(os.listdir(base)) if os.path.isdir(os.path.join(base, d))
             for f in sorted(os.listdir(os.path.join(base, d)))
             if f.endswith(".pbrt") and os.path.getsize(os.path.join(base, d, f)) < 20000]
    counts, found = {}, 0
    with tempfile.TemporaryDirectory(prefix="render-fuzz-") as work:
        mirror({os.path.dirname(f) for f in files}, work)
        out = os.path.join(work, "out.exr")
        for n in range(a.count):
            src = rng.choice(files)
            text = open(src).read()
            for _ in range(rng.choice([1, 1, 2, 3])):
                text = mutate(text, rng)
            path = os.path.join(work, os.path.basename(os.path.dirname(src)), "mutant-%d.pbrt" % n)
            with open(path, "w") as f:
                f.write(text)
            integrator = rng.choice(INTEGRATORS)
            cmd = [BIN, "render", path, "--outfile", out, "--nthreads", "2", "--quiet", "--spp", "2",
                   "--photons", "2000", "--integrator"] + integrator
            bad, err, ended = verdict(cmd, out, a.timeout)
            counts[ended] = counts.get(ended, 0) + 1
            if bad:
                found += 1
                os.makedirs(FOUND, exist_ok=True)
                keep = os.path.join(FOUND, "%s-%d-%d.pbrt" % (bad, a.seed, n))
                shutil.copy(path, keep)
                with open(keep + ".txt", "w") as f:
                    f.write("from %s, --integrator %s\n%s\n" % (src, " ".join(integrator), err[-3000:]))
                print("FOUND", bad, keep, flush=True)
            os.remove(path)
            if os.path.exists(out):
                os.remove(out)
    print("%d mutants, %d flagged: %s" % (a.count, found, counts))


if __name__ == "__main__":
    main()
