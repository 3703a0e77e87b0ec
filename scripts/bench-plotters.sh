#!/usr/bin/env bash
# host-sim's own SVG plots against plotters, the well-kept Rust plotting crate (issue 49): the
# curve family drawn by each from the same `host-sim curve --json`, with the same palette and
# labels (scripts/peers/plotters_family). Measures plotters' clean build (its crates only,
# SVG backend), each file's size, and each figure's labels: how many lie on a curve, overlap
# another or run off the page (scripts/peers/label_check.py, which reads the SVG back).
# Usage: scripts/bench-plotters.sh   (needs crates.io for plotters' first build)
# Environment: HOST_SIM=path uses that host-sim (default: target/release/host-sim, built).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "${HOST_SIM:-}" ]; then
    hs="$(realpath "$HOST_SIM")"
else
    cargo build --locked --release -q -p host-sim --bin host-sim
    hs=target/release/host-sim
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
peer=target/plotters-peer
rm -rf "$peer"
start=$(date +%s.%N)
cargo build --locked --release -q --manifest-path scripts/peers/plotters_family/Cargo.toml --target-dir "$peer"
built=$(echo "$(date +%s.%N) - $start" | bc)
"$hs" curve --prestretch-1 1.5:3:7 --prestretch-2 1.5:2.5:3 --out "$tmp/family" --json \
    >"$tmp/family.json" || [ $? -eq 1 ]
"$peer/release/plotters_family" "$tmp/family.json" "$tmp/plotters.svg"
colours=("#0072B2" "#E69F00" "#009E73")
printf 'plotters 0.3.7: a clean build of its crates (SVG backend) in %.1f s\n' "$built"
for f in "$tmp/family/curve.svg" "$tmp/plotters.svg"; do
    printf '%s: %s bytes\n' "$(basename "$f")" "$(wc -c <"$f")"
    python3 scripts/peers/label_check.py "$f" "${colours[@]}" | sed "s|$tmp/||"
done
