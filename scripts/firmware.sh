#!/usr/bin/env bash
# The firmware under QEMU (netduinoplus2, STM32F405): lint, build, check that the flashed
# table is what `host-sim lut` makes now, run the firmware and the on-target checks, and
# compare their decoded logs with the expected-output files (RTIC's way).
# Usage: scripts/firmware.sh [--bless]   (--bless rewrites the expected files)
set -euo pipefail
cd "$(dirname "$0")/.."
step() { printf '\n== %s\n' "$*"; }

step "the flashed table is the one host-sim makes"
cargo run --locked --release -q -p host-sim -- lut --out target/reference.bin >/dev/null
cmp tables/reference.bin target/reference.bin

cd firmware
step "firmware: fmt, clippy ($(rustc --version))"
cargo fmt -- --check
cargo clippy --locked --release --bins -- -D warnings
cargo clippy --locked --release --bins --no-default-features --features rtt -- -D warnings

for bin in firmware check; do
    step "run $bin in QEMU"
    status=0
    cargo run --locked --release -q --bin "$bin" >"../target/$bin.log" 2>&1 || status=$?
    cat "../target/$bin.log"
    if [ "${1:-}" = --bless ]; then
        cp "../target/$bin.log" "expected/$bin.log"
    fi
    if [ "$status" != 0 ]; then
        echo "$bin exited with status $status" >&2
        exit 1
    fi
    diff -u "expected/$bin.log" "../target/$bin.log"
done
echo "firmware logs match firmware/expected/"
