#!/usr/bin/env bash
# Times the README's two set-up commands as a newcomer runs them: clones this checkout's HEAD
# into a new folder beside it (so that ../shared/scenes is found as from the checkout), runs
# `cargo run --release -- render`, then `tools/test`, and prints how long each stage took.
# Run it on an otherwise idle machine; the crates and Python wheels should already be
# downloaded (else the downloads are timed too). The clone is left for inspection.
#
# Usage: tools/time-setup.sh [FOLDER]   (default: ../vcm-rs-setup-timing; must not exist)
# Set VCM_PYTHON=/nonexistent to time the tests without the Mitsuba cross-check, as on a
# machine without Mitsuba.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
folder=${1:-$(dirname "$repo")/vcm-rs-setup-timing}
if [ -e "$folder" ]; then
    echo "$folder exists: name another folder or remove it" >&2
    exit 2
fi
git clone --quiet "$repo" "$folder"
cd "$folder"
log=$folder/setup-timing.log

# Each output line, prefixed with the seconds since the epoch.
stamp() { while IFS= read -r line; do echo "$(date +%s) $line"; done; }

start=$(date +%s)
cargo run --release -- render 2>&1 | stamp > "$log"
rendered=$(date +%s)
tools/test 2>&1 | stamp >> "$log"
finished=$(date +%s)

# The time of the first line of `log` that matches $1.
at() { grep -m1 -E "^[0-9]+ $1" "$log" | cut -d' ' -f1; }
built=$(at '.*Running `target/release/vcm render`')
cargo_test=$(at '== cargo test')
first_binary=$(at ' +Running (unittests|tests/)')
maturin=$(at '== maturin')
pytest=$(at '== pytest')

row() { printf '| %s | %d min %02d s |\n' "$1" $(($2 / 60)) $(($2 % 60)); }
echo "| stage | time |"
echo "| --- | --- |"
row "render command: build" $((built - start))
row "render command: render" $((rendered - built))
row "test command: venv and pip" $((cargo_test - rendered))
row "build of the Rust tests" $((first_binary - cargo_test))
row "Rust tests" $((maturin - first_binary))
row "maturin" $((pytest - maturin))
row "pytest" $((finished - pytest))
row "test command in all" $((finished - rendered))
echo "(log: $log)"
