#!/usr/bin/env bash
# Builds the `vcm` binary with profile-guided optimization (PGO): an instrumented build
# renders a training set, and the final build lays out and inlines the code by what those
# renders ran. Images are bit for bit those of the plain release build; only the speed
# differs (docs/performance.md). Code the training does not reach is laid out as cold, so
# the training covers every integrator on every scene of `scenes/` (PT and VCM only on the
# large one), and PT and VCM on the third-party models of `../shared/scenes/` (textures,
# normal maps, OBJ) where they are present.
#
# Usage: tools/pgo-build.sh            (from anywhere; about twice a release build's time)
# A RUSTFLAGS of your own (e.g. "-C target-cpu=x86-64-v3" for a binary to copy elsewhere)
# replaces the default "-C target-cpu=native" in both builds.
# Result: target/pgo/optimized/release/vcm (under $CARGO_TARGET_DIR/pgo if that is set).
# Needs LLVM's llvm-profdata for the toolchain's LLVM: `rustup component add llvm-tools`.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

profdata=$(rustc --print target-libdir)/../bin/llvm-profdata
if [ ! -x "$profdata" ]; then
    echo "error: $profdata not found: install it with \`rustup component add llvm-tools\`" >&2
    exit 1
fi

out=${CARGO_TARGET_DIR:-$root/target}/pgo
profiles=$out/profiles
rm -rf "$profiles"
mkdir -p "$profiles"
# RUSTFLAGS replaces the rustflags of .cargo/config.toml, so its target CPU is named again
# unless the caller's RUSTFLAGS name their own.
cpu_flags=${RUSTFLAGS:--C target-cpu=native}

echo "1/3 instrumented build" >&2
RUSTFLAGS="$cpu_flags -C profile-generate=$profiles" \
    cargo build --release --locked -p vcm-rs --target-dir "$out/instrumented"
instrumented=$out/instrumented/release/vcm

echo "2/3 training renders" >&2
log=$out/training.log
: > "$log"
train() {
    "$instrumented" render "$@" -o "$profiles/train.exr" > /dev/null 2>> "$log" || {
        echo "error: training render \`vcm render $*\` failed; see $log" >&2
        exit 1
    }
}
for scene in scenes/*.gltf; do
    if [ "$(basename "$scene")" = large.gltf ]; then
        train "$scene" --algo pt --spp 2 --width 128 --height 128
        train "$scene" --algo vcm --spp 1 --width 128 --height 128
        continue
    fi
    for algo in pt lt bpt ppm bpm vcm; do
        train "$scene" --algo "$algo" --spp 4 --width 192 --height 192
    done
done
shared=../shared/scenes
for model in "$shared"/khronos-samples/*/glTF/*.gltf "$shared"/stanford-bunny/bunny.obj; do
    [ -f "$model" ] || continue
    for algo in pt vcm; do
        train "$model" --algo "$algo" --spp 4 --width 128 --height 128
    done
done
rm -f "$profiles"/train.exr "$profiles"/train.png
"$profdata" merge -o "$out/merged.profdata" "$profiles"

echo "3/3 optimized build" >&2
RUSTFLAGS="$cpu_flags -C profile-use=$out/merged.profdata" \
    cargo build --release --locked -p vcm-rs --target-dir "$out/optimized"
echo "built $out/optimized/release/vcm" >&2
