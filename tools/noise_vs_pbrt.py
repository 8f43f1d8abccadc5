#!/usr/bin/env python3
"""Noise against pbrt at an equal budget: renders a scene of pbrt-scenes/verify/ with
pbrt-sppm and with the matching pbrt (../shared/peers) at the scene's own iteration
count, several seeds each, and prints each render's relMSE and worst 4x4 tile against
the reference in tests/data/pbrt-ref/ (pbrt's own converged image), with medians and
the ratio of the medians.

    python3 tools/noise_vs_pbrt.py v4-rough-glass [--seeds 1 2 3] [--fix NAME,...]

pbrt-v3 takes its seed from the scene only, so v3 scenes are compared over pbrt-sppm's
seeds against pbrt-v3's one image. Build first: cargo build --release.
"""

import argparse
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OURS = ROOT / "target/release/pbrt-sppm"
IMGTOOL = ROOT / "target/release/pbrt-imgtool"
PEERS = ROOT.parent / "shared/peers"


def errors(image, reference):
    """(relMSE, worst tile %) of `image` against `reference`."""
    diff = subprocess.run([IMGTOOL, "diff", image, reference], capture_output=True, text=True, check=True).stdout
    tiles = subprocess.run([IMGTOOL, "tiles", image, reference], capture_output=True, text=True).stdout
    rel = float(re.search(r"relMSE ([0-9.e+-]+)", diff).group(1))
    worst = float(re.search(r"worst deviation ([0-9.]+)%", tiles).group(1))
    return rel, worst


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="a scene name in pbrt-scenes/verify/ (without .pbrt)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--fix", default="", help="pass --fix NAME,... to pbrt-sppm")
    args = ap.parse_args()
    scene = ROOT / "pbrt-scenes/verify" / f"{args.scene}.pbrt"
    reference = ROOT / "tests/data/pbrt-ref" / f"{args.scene}.exr"
    v4 = 'Film "rgb"' in scene.read_text() or 'Film "gbuffer"' in scene.read_text()
    rows = {"pbrt-sppm": [], "pbrt-v4" if v4 else "pbrt-v3": []}
    with tempfile.TemporaryDirectory() as tmp:
        # pbrt reads files relative to the scene: render a copy of the folder.
        work = Path(tmp) / "verify"
        shutil.copytree(scene.parent, work)
        for seed in args.seeds:
            ours = Path(tmp) / f"ours-{seed}.exr"
            cmd = [OURS, work / scene.name, "--quiet", "--seed", str(seed), "--outfile", ours]
            subprocess.run(cmd + (["--fix", args.fix] if args.fix else []), check=True)
            rows["pbrt-sppm"].append(errors(ours, reference))
            theirs = Path(tmp) / f"pbrt-{seed}.exr"
            if v4:
                peer = [PEERS / "pbrt-v4", "--seed", str(seed)]
            elif seed == args.seeds[0]:
                peer = [PEERS / "pbrt-v3"]
            else:
                continue
            subprocess.run(peer + ["--quiet", "--nthreads", "2", "--outfile", theirs, work / scene.name],
                           check=True, cwd=work, stdout=subprocess.DEVNULL)
            rows[list(rows)[1]].append(errors(theirs, reference))
    print(f"{args.scene}{' --fix ' + args.fix if args.fix else ''}: relMSE and worst tile against "
          f"{reference.relative_to(ROOT)}, seeds {' '.join(map(str, args.seeds))}")
    print("| renderer | relMSE per seed | median relMSE | worst tile per seed |")
    print("|---|---|---|---|")
    medians = []
    for name, r in rows.items():
        rel = [x[0] for x in r]
        medians.append(statistics.median(rel))
        print(f"| {name} | {', '.join(f'{x:.2e}' for x in rel)} | {medians[-1]:.2e} | "
              f"{', '.join(f'{x[1]:.2f}%' for x in r)} |")
    print(f"\nrelMSE median ratio, pbrt-sppm / pbrt: {medians[0] / medians[1]:.2f}")


if __name__ == "__main__":
    sys.exit(main())
