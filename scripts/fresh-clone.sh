#!/usr/bin/env bash
# A newcomer's first hour, timed: clone this repository's committed HEAD into a new folder,
# with an empty cargo home (so the registry is fetched and every crate built, as on CI's new
# machine), and time the README's two commands in it, one after the other.
# Usage: scripts/fresh-clone.sh [--main-only] [--keep] [--bare]
#   --main-only  time only the main command (`cargo run --release -p host-sim`)
#   --keep       leave the clone and its cargo home (default: removed at the end)
#   --bare       as on a machine without the tools: hides the cargo-installed tools
#                (defmt-print, cargo-fuzz) from PATH, then PURGES from this machine what the
#                test command installs (apt, with what came only for them: QEMU, picocom,
#                tmux, Chromium and its driver, gfortran, SUNDIALS; pip: numpy, SciPy,
#                matplotlib, Dask, pytest, selenium, the package, and pip's cache; the
#                rustup target thumbv7em-none-eabihf); the test command installs them again
# Prints a line per command, `main_seconds=… tests_seconds=…`, for BENCHMARKS.md.
# The rustup toolchain itself is not re-installed (rust-toolchain.toml names it; rustup has it).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
main_only=0 keep=0 bare=0
for a in "$@"; do
    case "$a" in
        --main-only) main_only=1 ;;
        --keep) keep=1 ;;
        --bare) bare=1 ;;
        -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "fresh-clone.sh: unknown argument \`$a\` (see --help)" >&2; exit 2 ;;
    esac
done
work="$(mktemp -d /tmp/fresh-clone.XXXXXX)"
[ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
git clone -q "$root" "$work/repo"
export CARGO_HOME="$work/cargo-home"
mkdir -p "$CARGO_HOME"
# The cargo-installed tools the test command would otherwise build (defmt-print, cargo-fuzz)
# stay reachable on PATH from the usual cargo home, as on a machine that already ran it once
# (but with --bare: only rustup's own proxies, and the new cargo home's bin, where the test
# command installs them).
if [ "$bare" = 1 ]; then
    # The PATH first (nothing removed yet if it cannot be made): rustup's proxies alone, then
    # the new cargo home's bin, where the test command installs its cargo tools.
    cargo_bin=$(dirname "$(command -v cargo)")
    proxies="$work/rustup-bin"
    mkdir -p "$proxies" "$CARGO_HOME/bin"
    for tool in cargo rustc rustdoc rustup cargo-clippy clippy-driver rustfmt cargo-fmt; do
        ln -s "$cargo_bin/$tool" "$proxies/$tool"
    done
    PATH="$CARGO_HOME/bin:$proxies:$(echo "$PATH" | tr : '\n' | grep -vxF "$cargo_bin" | paste -sd:)"
    export PATH
    # Then what the test command installs, purged with what came only for it, and pip's cache.
    SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get purge -y -qq --autoremove qemu-system-arm \
        picocom tmux chromium chromium-driver gfortran libsundials-dev >&2
    python3 -m pip uninstall -y -q numpy scipy matplotlib dask distributed pytest selenium \
        de-resonator >&2 || true
    python3 -m pip cache purge >&2 || true
    rustup target remove thumbv7em-none-eabihf >&2 || true
    for tool in qemu-system-arm picocom tmux chromium chromedriver defmt-print cargo-fuzz gfortran; do
        ! command -v "$tool" >/dev/null || { echo "fresh-clone.sh: $tool still on PATH" >&2; exit 1; }
    done
    for module in numpy scipy matplotlib dask pytest selenium de_resonator; do
        ! python3 -c "import $module" 2>/dev/null || { echo "fresh-clone.sh: $module still importable" >&2; exit 1; }
    done
fi
cd "$work/repo"
echo "fresh clone of $(git rev-parse --short HEAD) in $work/repo, CARGO_HOME=$CARGO_HOME" >&2
t0=$(date +%s)
cargo run --release -p host-sim >"$work/main.log" 2>&1 || { tail -20 "$work/main.log" >&2; exit 1; }
t1=$(date +%s)
main=$((t1 - t0))
echo "main command: cargo run --release -p host-sim: ${main} s" >&2
tests=skipped
if [ "$main_only" = 0 ]; then
    ./scripts/test-all.sh >"$work/tests.log" 2>&1 || { tail -30 "$work/tests.log" >&2; exit 1; }
    tests=$(($(date +%s) - t1))
    echo "test command: ./scripts/test-all.sh: ${tests} s (its steps: the table at the end of $work/tests.log)" >&2
    sed -n '/^== time per step/,$p' "$work/tests.log" >&2
fi
echo "main_seconds=$main tests_seconds=$tests"
