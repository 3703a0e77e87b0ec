#!/usr/bin/env bash
# The firmware under QEMU (netduinoplus2, STM32F405): lint every build, measure flash and RAM
# per feature set, count the tick's budget with the trim on, run the on-target checks against
# their expected log (RTIC's way), and run the product end to end: the command port, the DAC
# frames from QEMU's trace, a second device's image, bad images, the tick rate (in the
# background, beside what follows it); the same requests to the virtual board (host-sim
# serve) and the firmware, reply for reply; then every shipped scene with the firmware in the
# loop (its link build), tick for tick against the core.
# Usage: scripts/firmware.sh [--bless]   (--bless rewrites the expected log)
# HOST_SIM=path: the host-sim binary to use (default: build the release one).
set -euo pipefail
cd "$(dirname "$0")/.."
step() { printf '\n== %s\n' "$*"; }

step "the on-target checks' table is the one host-sim makes"
# HOST_SIM: a host-sim already built (test-all.sh passes the tests' own); else a release build.
if [ -z "${HOST_SIM:-}" ]; then
    cargo build --locked --release -q -p host-sim --features bdf
    HOST_SIM="$PWD/target/release/host-sim"
fi
HOST_SIM="$(realpath "$HOST_SIM")"
export HOST_SIM
host_sim="$HOST_SIM"
"$host_sim" lut --out target/reference.bin >/dev/null
cmp tables/reference.bin target/reference.bin
"$host_sim" lut --device devices/vhb-batch.toml --out target/vhb-batch.bin >/dev/null
cmp tables/vhb-batch.bin target/vhb-batch.bin

cd firmware
# The runs here end on their own; a hang ends at 5 minutes (qemu-run.sh has no limit unless told).
export QEMU_TIMEOUT="${QEMU_TIMEOUT:-300}"
step "firmware: fmt, clippy on every build ($(rustc --version))"
cargo fmt -- --check
# QEMU builds, and the silicon builds (HSE + PLL, RTT logs) that CI cannot run.
for f in qemu,log-semihosting qemu qemu,log-semihosting,model-sensor qemu,log-semihosting,link rtt; do
    cargo clippy --locked --release -q --bins --no-default-features --features "$f" -- -D warnings
done

step "feature sets: flash and static RAM (the budget: 256 KB of flash, sectors 0-5, and 32 KB of RAM; BENCHMARKS.md)"
sets=(qemu qemu,log-semihosting rtt)
names=("no logs" "+ defmt (QEMU default)" "silicon: RTT")
printf '%-24s %-30s %8s %8s\n' "set" "features" "flash" "RAM"
for i in "${!sets[@]}"; do
    f="${sets[$i]}"
    cargo build --locked --release -q --bin firmware --no-default-features --features "$f"
    # Flash: vector table, code, read-only data and .data's initial values; RAM: .data, .bss
    # and .uninit (the stack comes on top: `stack_bytes` in `status`).
    size -A target/thumbv7em-none-eabihf/release/firmware | awk -v n="${names[$i]}" -v f="$f" '
        $1 ~ /^\.(vector_table|text|rodata)$/ { flash += $2 }
        $1 == ".data" { flash += $2; ram += $2 }
        $1 ~ /^\.(bss|uninit)$/ { ram += $2 }
        END { printf "%-24s %-30s %8d %8d\n", n, f, flash, ram
              if (flash > 256 * 1024 || ram > 32 * 1024) { print "over 256 KB / 32 KB" > "/dev/stderr"; exit 1 } }'
done

step "the tick's budget: whole trim cycles (stretch; current only with λ from C under the probe) and a tracked drive counted under -icount"
QEMU_ICOUNT=1 cargo run --locked --release -q --bin count >../target/count-trim.log 2>&1 ||
    { cat ../target/count-trim.log; echo "count (trim, track) failed" >&2; exit 1; }
grep -E "trim|track|telemetry" ../target/count-trim.log
# The board's whole tick, the call the firmware's tick task makes (`Ticker::tick_block`: the
# ADC block through the image's front end, the controller, the DAC frame, a fault's entry)
# within the 1,500 instruction budget, every capability on: the trim on the
# stretch, the trim on the current only, the trim then the tracked drive, and the tracked
# drive's 3,000 ticks (BENCHMARKS.md).
board() { sed -n "s/^.*board tick with $1[^:]*: \([0-9]*\) instructions.*/\1/p" ../target/count-trim.log; }
trim=$(board "trim, worst over the cycle")
sensorless=$(board "sensorless trim")
cycle=$(board "trim then tracking")
tracking=$(board "tracking, worst over")
for n in "$trim" "$sensorless" "$cycle" "$tracking"; do
    if [ -z "$n" ] || [ "$(echo "$n" | wc -l)" -ne 1 ] || [ "$n" -gt 1500 ]; then
        echo "worst board ticks: trim ${trim:-unknown}, sensorless ${sensorless:-unknown}, trim then tracking ${cycle:-unknown}, tracking ${tracking:-unknown} (budget 1,500)" >&2
        exit 1
    fi
done
echo "worst board ticks: trim $trim, sensorless $sensorless, trim then tracking $cycle, tracking $tracking (budget 1,500)"

step "run the on-target checks in QEMU"
status=0
cargo run --locked --release -q --bin check >../target/check.log 2>&1 || status=$?
cat ../target/check.log
if [ "${1:-}" = --bless ]; then
    cp ../target/check.log expected/check.log
fi
if [ "$status" != 0 ]; then
    echo "check exited with status $status" >&2
    exit 1
fi
diff -u expected/check.log ../target/check.log
echo "on-target checks match firmware/expected/check.log"

step "the firmware for the end-to-end run (below, in the background): the default build and the model-sensor build"
elf=target/thumbv7em-none-eabihf/release/firmware
cargo build --locked --release -q --bin firmware --features model-sensor
cp "$elf" ../target/firmware-trim.elf
cargo build --locked --release -q --bin firmware

step "the one command from the root: scripts/qemu.sh (an image, QEMU, a console script; QEMU gone after)"
cd ..
printf 'start\nwait phase=holding 60\nstatus\nstop\n' >target/qemu-script.txt
scripts/qemu.sh -- --script target/qemu-script.txt | tee target/qemu-script.log
grep -q '^# ready .*power_up=wait' target/qemu-script.log
grep -q '^ok phase=holding target_hz=44 ' target/qemu-script.log
# RAM with the stack within 32 KB in this run too: the stack's high-water mark the board
# reports, on top of the build's static RAM.
stack=$(grep -o 'stack_bytes=[0-9]*' target/qemu-script.log | tail -1 | cut -d= -f2)
static=$(size -A firmware/target/thumbv7em-none-eabihf/release/firmware |
    awk '$1 == ".data" || $1 == ".bss" || $1 == ".uninit" { n += $2 } END { print n }')
echo "scripts/qemu.sh's run: RAM ${static} B static + ${stack:-?} B stack (budget 32,768 B)"
[ -n "$stack" ] && [ $((static + stack)) -le 32768 ] || { echo "over the 32 KB RAM budget" >&2; exit 1; }
sleep 0.5
if pgrep -f "unix:$PWD/target/qemu/fw.sock" | grep -q .; then echo "scripts/qemu.sh left QEMU running" >&2; exit 1; fi

step "a person at a serial terminal: picocom in tmux on the firmware's command port (scripts/qemu.sh --pty)"
HOST_SIM="$host_sim" python3 scripts/terminal_test.py qemu "$host_sim"

step "the live page against the firmware: host-sim dash in headless Chromium on scripts/qemu.sh --no-console"
HOST_SIM="$host_sim" python3 scripts/dash_test.py qemu "$host_sim"
cd firmware

# The end-to-end run, in the background from here: it waits on the firmware's clock and its
# replies most of the time (the whole QEMU part of this script kept a fifth of the two cores
# busy, 2026-12-07), so it runs beside the steps below, its QEMU under -icount (its own
# virtual time, whatever the load) on its own sockets (target/e2e/), with its own copy of the
# ELF (the link build below writes the same path); its log is shown when it ends, and it must
# pass. The runs above are in real time and measure the stack's high-water mark: alone.
cp "$elf" ../target/firmware-e2e.elf
python3 ../scripts/firmware_e2e.py "$PWD/../target/firmware-e2e.elf" "$host_sim" \
    "$PWD/../target/e2e" "$PWD/../target/firmware-trim.elf" >../target/e2e.log 2>&1 &
e2e_pid=$!
e2e_done() {
    [ -n "$e2e_pid" ] || return 0
    local status=0
    wait "$e2e_pid" || status=$?
    e2e_pid=""
    step "the firmware end to end: its log"
    cat ../target/e2e.log
    [ "$status" = 0 ] || { echo "firmware_e2e.py failed (status $status)" >&2; exit 1; }
}
# A failure below still shows the end-to-end log, and no QEMU of it is left running.
trap 'if [ -n "${e2e_pid:-}" ]; then kill "$e2e_pid" 2>/dev/null; echo "(the end-to-end run was stopped: target/e2e.log)" >&2; fi' EXIT

step "the virtual board against the firmware: one script of requests to host-sim serve and to QEMU, every reply compared field by field"
python3 ../scripts/differential.py "$PWD/$elf" "$host_sim"

step "the firmware in the loop: every shipped scene through the link build under QEMU, tick for tick against the core"
cargo build --locked --release -q --bin firmware --no-default-features --features qemu,log-semihosting,link
cp "$elf" ../target/firmware-link.elf
cd ..
rm -rf target/firmware-loop
python3 scripts/firmware_loop.py "$host_sim" target/firmware-link.elf target/firmware-loop

step "a board that refuses before any voltage: the firmware in the loop says the core's words"
# Two refusals at boot, made from shipped scenes: a target above a batch's guaranteed cap (the
# table's), and a drive at resonance with no damping told and no trim to measure Q (the
# swing's). Each report (its `refused` words), exit status, history and stream identical.
rm -rf target/refused target/firmware-loop-refused
mkdir -p target/refused
sed -e 's/^name = .*/name = "refused-batch-cap"/' -e 's/^target_hz = 45.5/target_hz = 44.0/' \
    scenes/batch-vhb.toml >target/refused/batch-cap.toml
sed -e 's/^name = .*/name = "refused-resonance"/' \
    -e 's/^ac_hz = 40.0/ac_hz = 44.0/' \
    scenes/reference.toml >target/refused/resonance.toml
python3 scripts/firmware_loop.py "$host_sim" target/firmware-link.elf target/firmware-loop-refused \
    target/refused/batch-cap.toml target/refused/resonance.toml
for s in batch-cap resonance; do
    "$host_sim" --json run "target/refused/$s.toml" --firmware target/firmware-link.elf \
        --out target/firmware-loop-refused/words >"target/refused/$s.json" 2>/dev/null || true
    python3 - "target/refused/$s.json" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
assert report["refused"], f"{sys.argv[1]}: the board did not refuse"
print("  refused, as the core:", report["refused"])
PY
done

cd firmware
e2e_done
