#!/usr/bin/env bash
# The GPU measured in one short run, for a machine with a GPU that is lent for minutes: PT,
# LT, BPT and VCM on the Cornell scenes and `large`, 1024² by default, with the GPU backend
# (rays traced on the GPU, shaded on the CPU), with PT, LT, BPT and VCM shaded on the GPU too
# (`--shading gpu`: whole paths in kernels) and with the CPU backend, on the same machine, as a
# Markdown table of
# samples/s, rays/s and where the time went (traversal, which on the GPU backend is the whole
# `Traversal` call with its transfers, and shading; with GPU shading all of it is "shading",
# and the GPU's time in the kernels, from timestamps, is its own column).
#
#   tools/gpu-bench.sh                        # builds `vcm` with cargo, then measures
#   VCM_BIN=path/to/vcm tools/gpu-bench.sh    # measures a binary built elsewhere
#
# Settings (environment): GPU_BENCH_SIZE (pixels per side, 1024), GPU_BENCH_SPP_PT (16; LT
# on the CPU takes as many), GPU_BENCH_SPP_SHADED (PT and LT shaded on the GPU, 256; BPT and
# VCM a quarter), GPU_BENCH_SPP_VCM (4; BPT on the CPU as many), GPU_BENCH_SCENES
# ("cornell-box cornell-water large"), GPU_BENCH_OUT (folder for the images, a new
# temporary one by default).
set -euo pipefail
cd "$(dirname "$0")/.."

size=${GPU_BENCH_SIZE:-1024}
scenes=${GPU_BENCH_SCENES:-cornell-box cornell-water large}
out=${GPU_BENCH_OUT:-$(mktemp -d)}
bin=${VCM_BIN:-}
if [ -z "$bin" ]; then
    cargo build --release --locked --quiet
    target_dir=$(cargo metadata --format-version 1 --no-deps --locked |
        sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')
    bin="$target_dir/release/vcm"
fi

echo "machine: $(nproc) CPU threads, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
if command -v nvidia-smi > /dev/null; then
    nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader |
        sed 's/^/gpu: /'
fi
echo "vcm: $bin, images in $out, ${size}², $(date -u +%Y-%m-%dT%H:%MZ)"
echo
echo "| scene | algo | backend | shading | spp | M samples/s | M rays/s | time split | GPU kernels |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
adapter=""
for scene in $scenes; do
    # algorithm, backend, shading, samples per pixel
    for run in "pt gpu gpu ${GPU_BENCH_SPP_SHADED:-256}" "pt gpu cpu ${GPU_BENCH_SPP_PT:-16}" \
        "pt cpu cpu ${GPU_BENCH_SPP_PT:-16}" "lt gpu gpu ${GPU_BENCH_SPP_SHADED:-256}" \
        "lt cpu cpu ${GPU_BENCH_SPP_PT:-16}" \
        "bpt gpu gpu $(( (${GPU_BENCH_SPP_SHADED:-256} + 3) / 4 ))" \
        "bpt cpu cpu ${GPU_BENCH_SPP_VCM:-4}" \
        "vcm gpu gpu $(( (${GPU_BENCH_SPP_SHADED:-256} + 3) / 4 ))" \
        "vcm gpu cpu ${GPU_BENCH_SPP_VCM:-4}" \
        "vcm cpu cpu ${GPU_BENCH_SPP_VCM:-4}"; do
        read -r algo backend shading spp <<< "$run"
        image="$out/$scene-$algo-$backend-$shading.exr"
        if ! log=$("$bin" render "scenes/$scene.gltf" --algo "$algo" --backend "$backend" \
            --shading "$shading" --width "$size" --height "$size" --spp "$spp" -o "$image" 2>&1); then
            echo "| $scene | $algo | $backend | $shading | $spp | failed: $(tail -n1 <<< "$log") | | | |"
            continue
        fi
        samples=$(grep -o '[0-9.]* M samples/s' <<< "$log" | head -n1 | cut -d' ' -f1)
        rays=$(grep '^rays:' <<< "$log" | grep -o '[0-9.]* M/s' | head -n1 | cut -d' ' -f1)
        split=$(grep '^time:' <<< "$log" | sed 's/^time: //')
        kernels=$(grep '^GPU kernels:' <<< "$log" | sed 's/^GPU kernels: //' || true)
        if [ "$backend" = gpu ] && [ -z "$adapter" ]; then
            adapter=$(grep -m1 '^traversal:' <<< "$log" || true)
        fi
        echo "| $scene | $algo | $backend | $shading | $spp | $samples | $rays | $split | $kernels |"
    done
done
echo
echo "${adapter:-traversal: no GPU run succeeded}"
