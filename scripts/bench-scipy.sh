#!/usr/bin/env bash
# A scene run, whole process, side by side: `host-sim simulate` (reference DOP853) against
# SciPy's solve_ivp (DOP853) on the same equations (scripts/scipy_scene.py, restated from
# model.md independently), at the same tolerance. Checks that both reach the same final
# state, then times each run from process start to exit.
# Usage: scripts/bench-scipy.sh [RUNS]   (installs SciPy into target/scipy-venv)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-10}
VENV=target/scipy-venv
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c "import scipy" 2>/dev/null; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install --quiet scipy
fi
cargo build --locked --profile peak -p host-sim --features bdf --quiet
"$VENV/bin/python" - "$RUNS" <<'PY'
import json, subprocess, sys, time
runs = int(sys.argv[1])
# The scene: reference device, 6000 V bias, 600 V AC at 40.2 Hz (0.9 f0), 1 s, tolerance 1e-12.
bias, ac, hz, seconds, tol = "6000", "600", "40.2", "1", "1e-12"
rust = ["target/peak/host-sim", "simulate", "--bias-volts", bias, "--ac-volts", ac,
        "--ac-hz", hz, "--duration-seconds", seconds, "--step-seconds", seconds, "--json"]
scipy = [sys.executable, "scripts/scipy_scene.py", bias, ac, hz, seconds, tol]

def timed(cmd):
    best, total, out = float("inf"), 0.0, None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        dt = time.perf_counter() - t0
        best, total = min(best, dt), total + dt
    return json.loads(out), best, total / runs

r, r_best, r_mean = timed(rust)
s, s_best, s_mean = timed(scipy)
diff = abs(r["final"]["stretch"] - s["final"]["stretch"])
print(f"scene: reference device, {bias} V + {ac} V at {hz} Hz, {seconds} s, DOP853 at {tol}")
print(f"final stretch  host-sim {r['final']['stretch']:.15f}  scipy {s['final']['stretch']:.15f}  |diff| {diff:.1e}")
print(f"{'':10}{'best s':>12}{'mean s':>12}")
print(f"{'host-sim':10}{r_best:12.4f}{r_mean:12.4f}")
print(f"{'scipy':10}{s_best:12.4f}{s_mean:12.4f}")
print(f"speed-up (best): {s_best / r_best:.0f}x over {runs} runs each")
if diff > 1e-9:
    sys.exit("the two final states disagree by more than 1e-9: not the same accuracy")
PY
