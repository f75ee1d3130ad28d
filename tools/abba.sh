#!/usr/bin/env bash
# Compares the render speed of two `vcm` binaries on this machine, interleaved (A B B A, so
# that a drift of the machine's speed during the runs weighs on both alike), and prints one
# Markdown table: per case, the median M samples/s of each binary, their range and B/A.
#
# Usage: tools/abba.sh A B [ROUNDS]        (ROUNDS of A B B A per case, default 3)
# Cases: ABBA_CASES="scene:algorithm:spp ..." (scenes/ names; default below), at
# ABBA_WIDTH pixels wide (default 384). Run from anywhere; the machine otherwise idle.
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: $0 A B [ROUNDS]" >&2
    exit 2
fi
a=$(realpath "$1")
b=$(realpath "$2")
rounds=${3:-3}
cases=${ABBA_CASES:-"cornell-box:pt:128 cornell-box:vcm:32 large:pt:32 large:vcm:16 cornell-water:pt:64"}
width=${ABBA_WIDTH:-384}
cd "$(dirname "$0")/.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# M samples/s of one render, from the summary line `vcm render` prints ("rendered S spp at
# W×H in T s: …"): samples over its render time, which has more digits than the rate it
# prints (two decimals: 1.3% steps at VCM's rates below 1 M samples/s).
speed() {
    "$1" render "scenes/$2.gltf" --algo "$3" --spp "$4" --width "$width" -o "$out/image.exr" 2>&1 |
        grep -o 'rendered [0-9]* spp at [0-9]*×[0-9]* in [0-9.]* s' |
        awk '{split($5, size, "×"); printf "%.4f\n", $2 * size[1] * size[2] / $7 / 1e6}'
}

echo "A: $a"
echo "B: $b"
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) threads; $rounds × ABBA, ${width} px wide"
echo
echo "| scene | algorithm | spp | A: M samples/s (range) | B: M samples/s (range) | B/A |"
echo "| --- | --- | --- | --- | --- | --- |"
for case in $cases; do
    IFS=: read -r scene algo spp <<< "$case"
    runs_a=()
    runs_b=()
    for _ in $(seq "$rounds"); do
        runs_a+=("$(speed "$a" "$scene" "$algo" "$spp")")
        runs_b+=("$(speed "$b" "$scene" "$algo" "$spp")")
        runs_b+=("$(speed "$b" "$scene" "$algo" "$spp")")
        runs_a+=("$(speed "$a" "$scene" "$algo" "$spp")")
    done
    python3 - "$scene" "$algo" "$spp" "${runs_a[*]}" "${runs_b[*]}" <<'EOF'
import statistics, sys
scene, algo, spp, a, b = sys.argv[1:]
a, b = [float(x) for x in a.split()], [float(x) for x in b.split()]
ma, mb = statistics.median(a), statistics.median(b)
print(f"| {scene} | {algo} | {spp} | {ma:.4g} ({min(a):.4g}–{max(a):.4g}) "
      f"| {mb:.4g} ({min(b):.4g}–{max(b):.4g}) | {mb / ma:.3f} |")
EOF
done
