#!/usr/bin/env bash
# Every check CI runs, from a fresh machine: installs what it needs, then formats, lints
# (host and Cortex-M4F target), builds the core for the target, runs all tests, the Python
# package's tests and examples, the two fuzzers, and runs the firmware under QEMU (installing
# qemu-system-arm, defmt-print, cargo-fuzz and the Python packages when missing). Ends with
# the time each step took.
# Usage: scripts/test-all.sh [--quick]
#   --quick  a developer's inner loop: format, clippy on the host, the workspace's tests
#            (no target builds, fuzzers or firmware; a few minutes once built)
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
case "${1:-}" in
    --quick) quick=1 ;;
    "") ;;
    -h|--help) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "test-all.sh: unknown argument \`$1\` (see --help)" >&2; exit 2 ;;
esac

TARGET=thumbv7em-none-eabihf
# Each step's name and seconds, printed as a table at the end (also when a step fails).
names=() seconds=() current="" started=0 begun=$(date +%s)
finish() {
    if [ -n "$current" ]; then
        names+=("$current")
        seconds+=($(($(date +%s) - started)))
    fi
    current=""
}
step() {
    finish
    current="$*" started=$(date +%s)
    printf '\n== %s\n' "$*"
}
table() {
    local status=$?
    finish
    printf '\n== time per step (s)\n'
    for i in "${!names[@]}"; do
        printf '%6d  %s\n' "${seconds[$i]}" "${names[$i]:0:90}"
    done
    printf '%6d  total%s\n' "$(($(date +%s) - begun))" "$([ "$status" = 0 ] || echo ", failed")"
}
trap table EXIT

if [ "$quick" = 1 ]; then
    step "format"
    cargo fmt --all -- --check
    step "clippy, host"
    cargo clippy --locked --workspace --all-targets --features host-sim/bdf -- -D warnings
    step "tests (the workspace's, with BDF, without the long fuzz test)"
    cargo test --locked --workspace --features host-sim/bdf -- --skip fuzz_the_controller
    exit 0
fi

step "toolchain (rust-toolchain.toml) and the $TARGET target"
rustup show active-toolchain
rustup component add clippy rustfmt
rustup target add "$TARGET"

step "the system's tools: QEMU, picocom and tmux, Chromium and its driver, selenium, the work-precision peers (installing in the background while the workspace builds), defmt-print"
# Network-bound, so they install beside the builds; awaited (tools_ready) before the first
# step that uses them, their log shown if they fail.
mkdir -p target
tools_log=target/tools-install.log
(
    set -euo pipefail
    missing=()
    for tool in qemu-system-arm:qemu-system-arm picocom:picocom tmux:tmux chromium:chromium chromedriver:chromium-driver; do
        command -v "${tool%%:*}" >/dev/null || missing+=("${tool##*:}")
    done
    if [ "${#missing[@]}" -gt 0 ]; then
        SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
        $SUDO apt-get update -qq
        $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
    fi
    # The browser tests' driver, pinned (4.53.0's dependencies do not install here; 4.51.0's do).
    python3 -c 'import selenium, sys; sys.exit(selenium.__version__ != "4.51.0")' 2>/dev/null ||
        python3 -m pip install --quiet --disable-pip-version-check selenium==4.51.0
    # The work-precision study's peers: SUNDIALS and gfortran, SciPy and numbalsoda at the
    # versions it names, into their own venv; CVODE's scene compiled.
    scripts/bench-peers.sh --install
) >"$tools_log" 2>&1 &
tools_pid=$!
tools_ready() {
    [ -n "$tools_pid" ] || return 0
    if ! wait "$tools_pid"; then
        cat "$tools_log" >&2
        echo "test-all.sh: installing the system's tools failed (above; $tools_log)" >&2
        exit 1
    fi
    tools_pid=""
    qemu-system-arm --version | head -1
    chromium --version 2>/dev/null
    python3 -c 'import selenium; print("selenium", selenium.__version__)'
}
if ! command -v defmt-print >/dev/null; then
    cargo install --locked defmt-print --version 1.2.0
fi
defmt-print --version

step "format"
cargo fmt --all -- --check

step "docs: every model.md citation names a section of docs/model.md; nothing points outside"
scripts/check-citations.sh

step "clippy, host (host-sim as built by default, and with its bdf feature; the core without its optional features)"
cargo clippy --locked --workspace --all-targets -- -D warnings
cargo clippy --locked --workspace --all-targets --features host-sim/bdf -- -D warnings
cargo clippy --locked -p de-resonator --all-targets --no-default-features -- -D warnings

step "clippy, target (core with defmt)"
cargo clippy --locked -p de-resonator --target "$TARGET" --features defmt -- -D warnings

step "build the no_std core for $TARGET"
cargo build --locked -p de-resonator --target "$TARGET" --release
cargo build --locked -p de-resonator --target "$TARGET" --release --features defmt

step "tests (core integration tests, host-sim unit and CLI tests with BDF; the fuzz test has its own step)"
cargo test --locked --workspace --features host-sim/bdf -- --skip fuzz_the_controller

step "a person at a serial terminal: picocom in tmux on host-sim serve --pty"
tools_ready
python3 scripts/terminal_test.py serve "$PWD/target/debug/host-sim"

step "the live page: host-sim dash in headless Chromium (selenium) against host-sim serve"
python3 scripts/dash_test.py serve "$PWD/target/debug/host-sim"

step "the core's tests without its optional trim feature (as the firmware builds it)"
cargo test --locked -q -p de-resonator --no-default-features -- --skip fuzz_the_controller

step "fuzz test: the f32 controller on random devices, settings, tables and sensors"
FUZZ_TICKS=3000000 cargo test --locked -q -p de-resonator --test fuzz -- --nocapture

step "cargo-fuzz: the table parser, the controller's boot and images and requests under libFuzzer (20 s, side by side), the Python package building beside it"
cargo fmt --manifest-path fuzz/Cargo.toml -- --check
# The Python package (its release build) builds while libFuzzer runs:
# awaited in the Python step, its log shown if it fails. The package and what its tests and
# examples use (numpy, SciPy, matplotlib, Dask), into the interpreter CI runs.
pip_log=target/pip-install.log
python3 -m pip install --quiet --disable-pip-version-check "./python[test]" >"$pip_log" 2>&1 &
pip_pid=$!
# 20 s, the three targets side by side (40 s less than one after another), keeps the test
# command within 15 minutes from a fresh clone on a bare machine; the long campaigns
# are BENCHMARKS.md's (FUZZ_SECONDS=… scripts/fuzz.sh).
FUZZ_SECONDS=20 FUZZ_PARALLEL=1 scripts/fuzz.sh

step "Python: pip install ./python (maturin, built beside libFuzzer), pytest python/tests, the examples' figures"
if ! wait "$pip_pid"; then
    cat "$pip_log" >&2
    echo "test-all.sh: pip install ./python failed (above; $pip_log)" >&2
    exit 1
fi
# The tests compare against the CLI the test step built.
HOST_SIM="$PWD/target/debug/host-sim" python3 -m pytest -q python/tests
python3 python/examples/figures.py --out out/python
python3 python/examples/studies.py --out out/python
python3 python/examples/monte_carlo.py --devices 5000 --workers 2 --plot out/python/monte-carlo.svg
python3 python/examples/monte_carlo.py --batch --devices 2000 --workers 2

step "docs/plots/: every figure the docs show is what its command makes now (scripts/plots.sh --check)"
HOST_SIM="$PWD/target/debug/host-sim" scripts/plots.sh --check

step "work-precision beside the peers: SciPy, numbalsoda, CVODE (scripts/bench-peers.sh --check against docs/plots/)"
HOST_SIM="$PWD/target/debug/host-sim" scripts/bench-peers.sh --check

step "firmware under QEMU: the reference run and the on-target checks against expected logs"
# host-sim as `cargo test` built it for its CLI tests (the test profile, optimised): no
# second build of the workspace in the release profile.
[ -x target/debug/host-sim ] || { echo "no target/debug/host-sim: the test step builds it" >&2; exit 1; }
HOST_SIM="$PWD/target/debug/host-sim" scripts/firmware.sh
