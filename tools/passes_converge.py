#!/usr/bin/env python3
"""Error against run time, classic SPPM beside independent passes (Knaus-Zwicker).

    python3 tools/passes_converge.py [--runs 3] [--scale 4] [--out target/passes] [SCENE.pbrt ...]

For each scene: a reference rendered with classic SPPM at --ref-scale x the scene's
iterations and a seed of its own (cached in --out), then --runs rounds, each running
classic and independent passes once (alternating, seeds 1..runs) for --scale x the
scene's iterations with ERRORS.csv. Prints, per scene, the median relMSE and seconds at
a quarter, a half and all of the iterations, and the mean of the last image over the
reference's. Both modes do the same work per iteration, so equal iterations are close
to equal time; the seconds are printed to show it.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "pbrt-sppm")
SUITE = [
    "pbrt-scenes/v3/sppm-bench.pbrt",
    "pbrt-scenes/v3/cornell-glass.pbrt",
    "pbrt-scenes/v3/caustic-ring.pbrt",
    "pbrt-scenes/verify/v3-caustic.pbrt",
    "pbrt-scenes/v3/keyhole.pbrt",
]


def iterations(scene):
    out = subprocess.run([BIN, "check", scene, "--json"], capture_output=True, text=True, check=True)
    import json

    return json.loads(out.stdout)["integrator"]["iterations"]


def render(scene, args, outfile):
    cmd = [BIN, "render", scene, "--nthreads", "2", "-q", "--outfile", outfile] + args
    subprocess.run(cmd, check=True)


def rows(path):
    with open(path) as f:
        return {int(r["iteration"]): r for r in csv.DictReader(f)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--scale", type=int, default=1, help="iterations: this many times the scene's")
    ap.add_argument("--ref-scale", type=int, default=16)
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "passes"))
    o = ap.parse_args()
    os.makedirs(o.out, exist_ok=True)
    print("| scene | iterations | relMSE classic (¼, ½, all) | relMSE independent (¼, ½, all) | independent / classic | seconds classic, independent |")
    print("|---|---|---|---|---|---|")
    for scene in o.scenes or SUITE:
        scene = os.path.join(ROOT, scene) if not os.path.isabs(scene) else scene
        name = os.path.splitext(os.path.basename(scene))[0]
        n = iterations(scene) * o.scale
        ref = os.path.join(o.out, f"{name}.ref{n * o.ref_scale}.exr")
        if not os.path.exists(ref):
            render(scene, ["--spp", str(n * o.ref_scale), "--seed", "9999"], ref)
        rungs = [max(1, n // 4), max(1, n // 2), n]
        got = {"classic": [], "independent": []}
        for run in range(1, o.runs + 1):
            for mode in ("classic", "independent"):
                csvp = os.path.join(o.out, f"{name}.{mode}.{run}.csv")
                img = os.path.join(o.out, f"{name}.{mode}.exr")
                render(scene, ["--spp", str(n), "--seed", str(run), "--passes", mode,
                               "--mse-reference-image", ref, "--mse-reference-out", csvp], img)
                got[mode].append(rows(csvp))
        med = {m: [statistics.median(float(r[k]["relmse"]) for r in got[m]) for k in rungs] for m in got}
        sec = {m: statistics.median(float(r[n]["seconds"]) for r in got[m]) for m in got}
        ratio = ", ".join(f"{i / c:.2f}" for c, i in zip(med["classic"], med["independent"]))
        fmt = lambda v: ", ".join(f"{x:.3g}" for x in v)
        print(f"| `{name}` | {n} | {fmt(med['classic'])} | {fmt(med['independent'])} | {ratio} | "
              f"{sec['classic']:.2f}, {sec['independent']:.2f} |", flush=True)


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import docsection

    sys.exit(docsection.run(main, "passes-converge"))
