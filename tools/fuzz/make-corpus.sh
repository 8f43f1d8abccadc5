#!/usr/bin/env bash
# Gathers the seed corpus of each fuzz target from files committed in the repository
# (bundled scenes, good and bad test scenes, PLYs, the image seeds, the NanoVDB test grid, the Ptex textures, the Fourier and measured BSDFs) into
# tools/fuzz/corpus/<target>/, the working corpus cargo fuzz grows (not committed).
set -euo pipefail
cd "$(dirname "$0")"
root=../..
mkdir -p corpus/statements corpus/builder corpus/ply corpus/image corpus/nanovdb corpus/ptex corpus/fourier corpus/measured
for f in "$root"/pbrt-scenes/v3/*.pbrt "$root"/pbrt-scenes/v4/*.pbrt "$root"/tests/data/good/*.pbrt "$root"/tests/data/bad/*.pbrt; do
    name=$(basename "$(dirname "$f")")-$(basename "$f")
    cp "$f" corpus/statements/"$name"
    cp "$f" corpus/builder/"$name"
done
for f in "$root"/pbrt-scenes/v3/geometry/*.ply "$root"/tests/data/bad/*.ply; do
    cp "$f" corpus/ply/"$(basename "$f")"
done
cp seeds/image/* corpus/image/
cp "$root"/tests/data/nanovdb/*.nvdb corpus/nanovdb/
cp "$root"/pbrt-scenes/verify/textures/*.ptx corpus/ptex/
cp "$root"/pbrt-scenes/verify/bsdfs/glazed.bsdf corpus/fourier/
cp "$root"/pbrt-scenes/verify/bsdfs/rosegold.bsdf "$root"/pbrt-scenes/verify/bsdfs/anodized.bsdf corpus/measured/
cp regressions/*/* corpus/ 2>/dev/null || true
echo "corpus ready: $(find corpus -type f | wc -l) files"
