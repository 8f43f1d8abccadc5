#!/bin/sh
# Builds pbrt-v4 (mmp/pbrt-v4 at 5f7a606, CPU only) from git snapshots, for a machine
# whose CPU the ready-made ../shared/peers/pbrt-v4 does not run on (it was built with
# AVX-512). An oracle for comparisons only: nothing in our build or tests needs it.
#
#   tools/build-pbrt-v4.sh OUT_DIR        # then OUT_DIR/build/pbrt (about 10 minutes
#                                         # on 2 cores)
#
# MIRROR (default /work/.mirror) holds bare snapshots named owner+repo/repo, as the
# library's `fetch` makes them: mmp/pbrt-v4 and the submodules listed below. Needs
# cmake, g++, libopenexr-dev, zlib1g-dev, libgl1-mesa-dev and the X11 headers
# (libx11-dev libxrandr-dev libxinerama-dev libxcursor-dev libxi-dev).
#
# The snapshot lacks two generated tables (blue noise, pmj02bn points); they are
# filled with random numbers, which only the `pmj02bn` sampler and 8-bit dithering
# read. Measured: its 256-sample images of v4-coat and v4-difftrans are within 0.83%
# and 0.56% (worst 4x4 tile) of the references made by the peers' binary.
set -eu
out=${1:?usage: build-pbrt-v4.sh OUT_DIR}
mirror=${MIRROR:-/work/.mirror}
src=$out/src
rm -rf "$src" && mkdir -p "$src"

# Writes every blob of `commit` in git dir $1 under $2, skipping absent ones.
extract() {
    git -C "$1" ls-tree -r "$3" | while read -r _ type sha path; do
        [ "$type" = blob ] || continue
        mkdir -p "$2/$(dirname "$path")"
        git -C "$1" cat-file blob "$sha" > "$2/$path" 2>/dev/null || { echo "absent: $path"; rm -f "$2/$path"; }
    done
}

extract "$mirror/mmp+pbrt-v4/repo" "$src" 5f7a6068
for m in "ptex wdas+ptex 054047d02b9e06e690420b407114d2872435b953" \
         "double-conversion mmp+double-conversion HEAD" \
         "libdeflate mmp+libdeflate 1fd0bea6ca2073c68493632dafc4b1ddda1bcbc3" \
         "utf8proc JuliaStrings+utf8proc d7bf128df773c2a1a7242eb80e51e91a769fc985" \
         "qoi phoboslab+qoi 028c75fd26e5e0758c7c711216c00404994c1ad3" \
         "stb nothings+stb af1a5bc352164740c1cc1354942b1c6b72eacb8a" \
         "filesystem wjakob+filesystem c5f9de30142453eb3c6fe991e82dfc2583373116" \
         "lodepng lvandeve+lodepng 8c6a9e30576f07bf470ad6f09458a2dcd7a6a84a" \
         "glfw glfw+glfw 7b6aead9fb88b3623e3b3725ebb42670cbe4c579" \
         "openvdb AcademySoftwareFoundation+openvdb 414bed84c2fc22e188eac7b611aa85c7edd7a5a9"; do
    set -- $m
    extract "$mirror/$2/repo" "$src/src/ext/$1" "$3"
done
# double-conversion's tests are absent from its snapshot; pbrt only needs the library.
for f in gay-fixed gay-precision gay-shortest; do
    echo > "$src/src/ext/double-conversion/test/cctest/$f.cc"
done
mkdir -p "$src/src/ext/openexr/src"   # the system's OpenEXR is used

python3 - "$src" <<'EOF'
import random, sys
src = sys.argv[1]
random.seed(1)
def table(path, head, n, bits, suffix):
    with open(path, "w") as f:
        f.write(head)
        vals = [str(random.getrandbits(bits)) + suffix for _ in range(n)]
        for i in range(0, n, 32):
            f.write(",".join(vals[i:i + 32]) + ",\n")
        f.write("};\n}\n")
table(src + "/src/pbrt/util/bluenoise.cpp",
      "#include <pbrt/util/bluenoise.h>\nnamespace pbrt {\nPBRT_CONST uint16_t BlueNoiseTextures"
      "[NumBlueNoiseTextures][BlueNoiseResolution][BlueNoiseResolution] = {\n", 48 * 128 * 128, 16, "")
table(src + "/src/pbrt/util/pmj02tables.cpp",
      "#include <pbrt/util/pmj02tables.h>\nnamespace pbrt {\nPBRT_CONST uint32_t pmj02bnSamples"
      "[nPMJ02bnSets][nPMJ02bnSamples][2] = {\n", 5 * 65536 * 2, 32, "u")
EOF

# The submodule checks compare git revisions, which snapshots do not have.
sed -i 's/^function (CHECK_EXT NAME DIR HASH)$/function (CHECK_EXT NAME DIR HASH)\n  return ()/' "$src/CMakeLists.txt"
mkdir -p "$out/build"
cd "$out/build"
cmake ../src -DCMAKE_BUILD_TYPE=Release -DGLFW_BUILD_WAYLAND=OFF -DBUILD_TESTING=OFF
make -j"$(nproc)" pbrt_exe
