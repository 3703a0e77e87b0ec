#!/usr/bin/env bash
# Every figure in docs/plots/, made again by the commands that make it, from the built-in
# reference device and the shipped scenes. With --check (CI), made in a scratch folder and
# compared with the committed ones instead: byte for byte (the SVGs' positions are written to
# a hundredth of a pixel, so the last bits of a float do not move them), except
#   work-precision.svg        its x axis is measured run time (its ticks move with it):
#                             compared by its words but numbers (titles, axes, series);
#                             the speeds are measured, BENCHMARKS.md
#   python-tuning-family.svg  matplotlib's: compared by its words (titles, labels, ticks,
#                             legend); its curves are the Python tests' (python/tests)
# work-precision-peers.svg and work-precision-peers-whole.svg (and their CSV) are
# scripts/bench-peers.sh's, which makes and checks them with the peers installed.
# A figure that drifted is named, with the command that makes it; `scripts/plots.sh` (no
# --check) writes them all to docs/plots/.
# Usage: scripts/plots.sh [--check]
# Environment: HOST_SIM=path uses that host-sim (default: the release build, with bdf);
# the Python figure needs the package installed (pip install ./python), else it is skipped
# with a note (--check: an error).
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
case "${1:-}" in
    --check) check=1 ;;
    "") ;;
    -h|--help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "plots.sh: unknown argument \`$1\` (see --help)" >&2; exit 2 ;;
esac
if [ -n "${HOST_SIM:-}" ]; then
    hs="$(realpath "$HOST_SIM")"
else
    cargo build --locked --release -q -p host-sim --features bdf --bin host-sim --example sensorless_noise
    hs=target/release/host-sim
fi
# The example beside the binary (`cargo test` builds it with the tests' host-sim).
example="$(dirname "$hs")/examples/sensorless_noise"
[ -x "$example" ] || { echo "plots.sh: no $example (cargo test, or cargo build --example sensorless_noise, builds it)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=docs/plots
[ "$check" = 1 ] && out="$tmp/plots"
mkdir -p "$out"
# Exit status 1 is a finding (a limit crossed, a fault), not a failure of this script.
ran() { "$hs" "$@" >/dev/null 2>&1 || [ $? -eq 1 ]; }
ran curve --target-hz 44 --out "$tmp/curve" && cp "$tmp/curve/curve.svg" "$out/curve.svg"
ran curve --prestretch-1 1.5:3:7 --prestretch-2 1.5:2.5:3 --out "$tmp/family" \
    && cp "$tmp/family/curve.svg" "$out/curve-family.svg"
ran run --out "$tmp/run" && cp "$tmp/run/reference/run.svg" "$out/run.svg"
ran run scenes/fault-sensor-stuck.toml --out "$tmp/run" \
    && cp "$tmp/run/fault-sensor-stuck/run.svg" "$out/run-fault.svg"
ran sweep --out "$tmp/sweep" && cp "$tmp/sweep/sweep.svg" "$out/sweep.svg"
# The nonlinear studies at the bias of the reference job's 44 Hz, Q 100.
ran poincare --bias-volts 7450 --ac-volts 1200 --ac-hz 85 --quality-factor 100 --periods 150 \
    --y0 "2.19,0;2.3,0;2.05,-40" --out "$tmp/poincare" \
    && cp "$tmp/poincare/poincare.svg" "$out/poincare.svg"
ran bifurcation --bias-volts 7450 --ac-volts 200 --vary ac-hz --values 40:47:71 \
    --quality-factor 100 --periods 10 --transient-periods 300 --out "$tmp/bif-hz" \
    && cp "$tmp/bif-hz/bifurcation.svg" "$out/bifurcation-frequency.svg"
ran bifurcation --bias-volts 7450 --ac-hz 88 --vary ac-volts --values 0:1500:61 \
    --quality-factor 100 --periods 20 --transient-periods 300 --out "$tmp/bif-ac" \
    && cp "$tmp/bif-ac/bifurcation.svg" "$out/bifurcation-amplitude.svg"
ran drive-map --quality-factor 100 --ac-volts 0:3000:13 --ac-hz 13:106:32 --periods 80 \
    --out "$tmp/drive-map" && cp "$tmp/drive-map/drive-map.svg" "$out/drive-map.svg"
ran simulate --bias-volts 9400 --start prestretch --duration-seconds 0.05 \
    --plot "$out/simulate-crossing.svg"
ran report --out "$tmp/report" && cp "$tmp/report/work-precision.svg" "$out/work-precision.svg"
"$example" "$out/sensorless-noise.svg" >/dev/null
if python3 -c 'import de_resonator' 2>/dev/null; then
    python3 python/examples/figures.py --out "$tmp/python" >/dev/null
    cp "$tmp/python/tuning-family.svg" "$out/python-tuning-family.svg"
elif [ "$check" = 1 ]; then
    echo "plots.sh: the Python package is not installed (pip install ./python)" >&2
    exit 1
else
    echo "plots.sh: python-tuning-family.svg kept as it was (pip install ./python to remake it)" >&2
fi
if [ "$check" = 0 ]; then
    ls -l "$out"
    exit 0
fi
# The comparison: each committed figure against the one made now.
words() { grep -o '<text[^>]*>[^<]*' "$1" | sed 's/<text[^>]*>//'; }
# The words but numbers (tick labels: 0.5, 2e3, 10⁻³), read as UTF-8 whatever the locale.
names() {
    python3 -c 'import re, sys
for t in re.findall(r"<text[^>]*>([^<]*)", open(sys.argv[1], encoding="utf-8").read()):
    if not re.fullmatch(r"[-+0-9.,eE×·^ ⁰¹²³⁴⁵⁶⁷⁸⁹⁻]*", t):
        print(t)' "$1"
}
drifted=0
for made in "$out"/*.svg; do
    name=$(basename "$made")
    kept="docs/plots/$name"
    case "$name" in
        work-precision.svg) same() { cmp -s <(names "$kept") <(names "$made"); } ;;
        python-tuning-family.svg) same() { cmp -s <(words "$kept") <(words "$made"); } ;;
        *) same() { cmp -s "$kept" "$made"; } ;;
    esac
    if [ ! -f "$kept" ] || ! same; then
        echo "plots.sh: docs/plots/$name differs from what its command makes now" >&2
        drifted=1
    fi
done
for kept in docs/plots/*.svg; do
    case "$kept" in docs/plots/work-precision-peers*) continue ;; esac
    [ -f "$out/$(basename "$kept")" ] || { echo "plots.sh: nothing makes $kept" >&2; drifted=1; }
done
if [ "$drifted" = 1 ]; then
    echo "plots.sh: run scripts/plots.sh and commit docs/plots/ (each figure read before)" >&2
    exit 1
fi
echo "plots.sh: the $(ls "$out" | wc -l) figures in docs/plots/ are what their commands make"
