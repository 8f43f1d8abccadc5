#!/bin/bash
# Builds pbrt-sppm with profile-guided optimisation: an instrumented build renders the
# bundled scenes briefly, and the release build is laid out by what those renders ran.
# Opt-in; the normal build and the tests never need it. About 7 minutes on 2 cores.
#
#   tools/pgo-build.sh            # then target/pgo/use/release/pbrt-sppm
#   tools/pgo-build.sh --install  # and copy it over ~/.cargo/bin/pbrt-sppm
#
# Needs llvm-profdata of the compiler's own LLVM: `rustup component add llvm-tools`.
# Images are bit for bit those of the plain build; only the speed changes. Measured
# gains (docs/benchmarks.md, "Profile-guided builds" and the sections after it): 0.81
# of the plain build's wall time on sppm-bench, also when it is left out of the
# training, and 0.86 on caustic-glass f16-9a, which it does not train on (both for
# AVX2, AMD EPYC, 7 December).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD/target/pgo
install=false
case "${1:-}" in
--install) install=true ;;
"") ;;
*) echo "usage: tools/pgo-build.sh [--install]" >&2; exit 2 ;;
esac

host=$(rustc -vV | sed -n 's/^host: //p')
profdata=$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-profdata
if [ ! -x "$profdata" ]; then
    echo "error: $profdata not found; run: rustup component add llvm-tools" >&2
    exit 1
fi

# Stale counts from an earlier run would be merged in: start from nothing.
rm -rf "$root/data" "$root/out" && mkdir -p "$root/data" "$root/out"
echo "1/3 instrumented build"
RUSTFLAGS="${RUSTFLAGS:-} -Cprofile-generate=$root/data" \
    cargo build --release --locked --quiet --target-dir "$root/gen" --bin pbrt-sppm

echo "2/3 training renders"
bin=$root/gen/release/pbrt-sppm
render() { timeout 300 "$bin" render "$@" --outfile "$root/out/o.exr" --quiet >/dev/null 2>&1 || true; }
for scene in pbrt-scenes/v3/*.pbrt pbrt-scenes/v4/*.pbrt pbrt-scenes/verify/*.pbrt; do
    render "$scene" --spp 2
    timeout 60 "$bin" check "$scene" >/dev/null 2>&1 || true
done
render pbrt-scenes/v3/sppm-bench.pbrt --spp 16
for integrator in vcm bdpt; do
    render pbrt-scenes/v3/doorway.pbrt --spp 4 --integrator "$integrator"
    render pbrt-scenes/v3/cornell-glass.pbrt --spp 8 --integrator "$integrator"
done
"$profdata" merge -o "$root/merged.profdata" "$root/data"

echo "3/3 optimised build"
RUSTFLAGS="${RUSTFLAGS:-} -Cprofile-use=$root/merged.profdata" \
    cargo build --release --locked --quiet --target-dir "$root/use" --bin pbrt-sppm
echo "built $root/use/release/pbrt-sppm"
if $install; then
    mkdir -p "$HOME/.cargo/bin"
    cp "$root/use/release/pbrt-sppm" "$HOME/.cargo/bin/pbrt-sppm"
    echo "installed $HOME/.cargo/bin/pbrt-sppm"
fi
