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
cargo clippy --locked --release --bins --no-default-features --features rtt,solver,dynamics \
    -- -D warnings
cargo clippy --locked --release --bins --features trim -- -D warnings

# The feature sets, smallest first: each must run the reference job to status 0.
tiers=(qemu qemu,solver qemu,solver,dynamics qemu,solver,dynamics,log-semihosting)
names=("table only" "+ solver" "+ dynamics" "+ defmt")
step "feature sets: clippy, run in QEMU (status 0), flash and static RAM"
printf '%-12s %-40s %8s %8s\n' "set" "features" "flash" "RAM"
for i in "${!tiers[@]}"; do
    f="${tiers[$i]}"
    cargo clippy --locked --release -q --bin firmware --no-default-features --features "$f" \
        -- -D warnings
    cargo run --locked --release -q --bin firmware --no-default-features --features "$f" \
        >"../target/tier.log" 2>&1 || { cat ../target/tier.log; echo "[$f] failed" >&2; exit 1; }
    # Flash: code, read-only data and the initial values of .data; RAM: .data and .bss (the
    # stack comes on top: see the count binary).
    size -A target/thumbv7em-none-eabihf/release/firmware | awk -v n="${names[$i]}" -v f="$f" '
        $1 ~ /^\.(vector_table|text|rodata)$/ { flash += $2 }
        $1 == ".data" { flash += $2; ram += $2 }
        $1 ~ /^\.(bss|uninit)$/ { ram += $2 }
        END { printf "%-12s %-40s %8d %8d\n", n, f, flash, ram
              if (flash > 48 * 1024 || ram > 8 * 1024) { print "over 48 KB / 8 KB" > "/dev/stderr"; exit 1 } }'
done

step "the tick's budget with the trim on: a whole trim cycle counted under -icount"
QEMU_ICOUNT=1 cargo run --locked --release -q --bin count --features trim >../target/count-trim.log 2>&1 ||
    { cat ../target/count-trim.log; echo "count (trim) failed" >&2; exit 1; }
grep -E "trim" ../target/count-trim.log
worst=$(sed -n 's/.*worst over a whole trim cycle: \([0-9]*\) instructions.*/\1/p' ../target/count-trim.log)
if [ -z "$worst" ] || [ "$worst" -ge 1500 ]; then
    echo "the worst tick of a trim cycle is ${worst:-unknown} instructions: the budget is 1,500" >&2
    exit 1
fi

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
