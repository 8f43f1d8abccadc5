#!/usr/bin/env python3
"""Renders every scene of ../shared/scenes with pbrt-sppm and with the matching pbrt
(v3 or v4, from ../shared/peers) at equal SPPM settings and prints a Markdown table:
our warnings, and the image difference (whole-image channel means, worst 4x4 tile,
relMSE of ours against pbrt's).

Both renderers get the same copy of each scene, changed only so the comparison is
quick and like for like: the resolution divided by --shrink, and the Integrator
replaced by SPPM with the scene's own maxdepth, radius and photon count (capped) and
--iterations iterations (pbrt renders a non-SPPM integrator otherwise, which converges
to the same image only for some of them). The copy lives in a temporary folder whose
other files are links to those of the scene's collection.

    python3 tools/real_scenes.py [--iterations 16] [--shrink 4] [--photons 100000]
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared"
OURS = ROOT / "target/release/pbrt-sppm"
IMGTOOL = ROOT / "target/release/pbrt-imgtool"

INTEGRATOR = re.compile(
    r'Integrator\s+"[^"]*"(\s*"[^"]*"\s*(\[[^\]]*\]|"[^"]*"|[-+0-9.eE]+))*', re.S
)


def run(cmd, cwd=None, timeout=900):
    t0 = time.time()
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    return p, time.time() - t0


def scenes():
    """Top-level scene files: those with a WorldBegin of their own."""
    for p in sorted((SHARED / "scenes").rglob("*.pbrt")):
        text = p.read_text(errors="replace")
        if re.search(r"^\s*WorldBegin", text, re.M):
            yield p


def shrink(text, factor):
    def res(m):
        return f'{m.group(1)}[ {max(1, int(m.group(3)) // factor)} ]'

    return re.sub(r'("integer\s+[xy]resolution"\s*)(\[\s*)?(\d+)(\s*\])?', res, text)


def prepared_copy(scene, tmp, check, args):
    """A linked copy of the scene's folder with the main file rewritten."""
    rel = scene.relative_to(SHARED / "scenes")
    collection = SHARED / "scenes" / rel.parts[0]
    shutil.copytree(collection, Path(tmp) / rel.parts[0], copy_function=os.symlink)
    target = Path(tmp) / rel
    text = scene.read_text(errors="replace")
    integ = check["integrator"]
    v3 = check["syntax"] == "v3"
    photons = min(integ["photonsperiteration"], args.photons)
    line = f'Integrator "sppm" "integer maxdepth" {integ["maxdepth"]} "float radius" {integ["radius"]} ' \
        f'"integer photonsperiteration" {photons}'
    if v3:
        line += f' "integer numiterations" {args.iterations}'
    text = INTEGRATOR.sub("", text)
    text = re.sub(r"^(\s*)WorldBegin", line + r"\n\1WorldBegin", text, count=1, flags=re.M)
    text = shrink(text, args.shrink)
    target.unlink()
    target.write_text(text)
    return target, v3


def compare(ours, theirs):
    tiles, _ = run([str(IMGTOOL), "tiles", str(ours), str(theirs)])
    worst = tiles.stdout.strip().splitlines()[-1] if tiles.stdout.strip() else tiles.stderr.strip()
    m = re.search(r"worst deviation ([0-9.]+)%", worst)
    diff, _ = run([str(IMGTOOL), "diff", "--json", str(ours), str(theirs)])
    d = json.loads(diff.stdout) if diff.returncode in (0, 1) and diff.stdout.startswith("{") else {}
    return (float(m.group(1)) if m else None), d


def means(path):
    p, _ = run([str(IMGTOOL), "info", str(path)])
    found = re.findall(r"^([RGB]): .* mean ([-+0-9.eE]+)$", p.stdout, re.M)
    return [float(m) for _, m in found] if len(found) == 3 else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--iterations", type=int, default=16)
    ap.add_argument("--shrink", type=int, default=4)
    ap.add_argument("--photons", type=int, default=100_000)
    ap.add_argument("--only", default="", help="substring of the scene paths to run")
    args = ap.parse_args()
    rows = []
    for scene in scenes():
        rel = scene.relative_to(SHARED / "scenes")
        if args.only not in str(rel):
            continue
        check, _ = run([str(OURS), "check", "--json", str(scene)])
        if check.returncode != 0:
            rows.append((str(rel), "—", check.stderr.strip().splitlines()[-1], "", "", ""))
            continue
        c = json.loads(check.stdout)
        warnings = [w["message"] for w in c["warnings"]]
        with tempfile.TemporaryDirectory() as tmp:
            target, v3 = prepared_copy(scene, tmp, c, args)
            peer = SHARED / "peers" / ("pbrt-v3" if v3 else "pbrt-v4")
            ours_exr, theirs_exr = Path(tmp) / "ours.exr", Path(tmp) / "theirs.exr"
            spp = [] if v3 else ["--spp", str(args.iterations)]
            o, to = run([str(OURS), "render", str(target), "--outfile", str(ours_exr), "-q"] + spp, cwd=target.parent)
            p, tp = run([str(peer), "--quiet", "--nthreads", "2", "--outfile", str(theirs_exr)] + spp + [str(target)],
                        cwd=target.parent)
            if o.returncode != 0 or p.returncode != 0 or not theirs_exr.exists():
                why = (o.stderr if o.returncode else p.stderr).strip().splitlines()
                rows.append((str(rel), c["syntax"], f"render failed: {why[-1] if why else '?'}", "", "", ""))
                continue
            worst, d = compare(ours_exr, theirs_exr)
            mo, mt = means(ours_exr), means(theirs_exr)
            ratio = " ".join(f"{a / b:.3f}" if b else "—" for a, b in zip(mo, mt)) if mo and mt else "?"
            distinct = sorted(set(re.sub(r"\d+", "N", w) for w in warnings))
            wtext = f"{len(warnings)}: " + "; ".join(distinct) if warnings else "none"
            rows.append((str(rel), c["syntax"], wtext, ratio, f"{worst:.1f}%" if worst is not None else "?",
                         f"{d.get('relmse', float('nan')):.2e} ({to:.1f} s / {tp:.1f} s)"))
        print(" | ".join(rows[-1]), file=sys.stderr)
    print(f"| scene | syntax | our warnings | mean ours/pbrt (R G B) | worst tile | relMSE vs pbrt (time ours / pbrt) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import docsection

    sys.exit(docsection.run(main, "real-scenes"))
