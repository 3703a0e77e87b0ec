#!/usr/bin/env bash
# Regenerate the plots the README shows (docs/plots/), from the built-in reference device.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --locked --release -q -p host-sim --features bdf
hs=target/release/host-sim
out=docs/plots
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
# Exit status 1 is a finding (a limit crossed), not a failure of this script.
ran() { "$hs" "$@" >/dev/null || [ $? -eq 1 ]; }
ran curve --target-hz 44 --out "$tmp/curve" && cp "$tmp/curve/curve.svg" "$out/curve.svg"
ran curve --prestretch-1 1.5:3:7 --prestretch-2 1.5:2.5:3 --out "$tmp/family" \
    && cp "$tmp/family/curve.svg" "$out/curve-family.svg"
ran run --out "$tmp/run" && cp "$tmp/run/reference/run.svg" "$out/run.svg"
ran run scenes/fault-sensor-stuck.toml --out "$tmp/run" \
    && cp "$tmp/run/fault-sensor-stuck/run.svg" "$out/run-fault.svg"
ran sweep --out "$tmp/sweep" && cp "$tmp/sweep/sweep.svg" "$out/sweep.svg"
ran simulate --bias-volts 9400 --start prestretch --duration-seconds 0.05 \
    --plot "$out/simulate-crossing.svg"
ran report --out "$tmp/report" && cp "$tmp/report/work-precision.svg" "$out/work-precision.svg"
ls -l "$out"
