"""A bifurcation diagram side by side with SciPy, in one run (BENCHMARKS.md, "Python: a
bifurcation diagram against SciPy").

    python python/bench/bifurcation.py [--values 501] [--scipy-values 501]

The reference device at the bias of the reference job (7450 V, f0 44 Hz), Q 100, driven at
2·f0 with the AC amplitude from 0 to 1500 V (period doubling): --values values, 200 drive
periods a value (150 of transient, 50 section points), by continuation. `dr.bifurcation`
walks up (one core) and both ways (two walks on the two cores); SciPy's `solve_ivp` (DOP853,
the equation of docs/model.md §4 in python/tests/model.py) walks up over the first
--scipy-values values at the same tolerance (1e-10), each value from the last one's end, its
time scaled to --values when fewer. The section points are compared where both ran, as sets
(a period-2 orbit's two points alternate).
Prints a Markdown table.
"""

import argparse
import pathlib
import sys
import time

import numpy as np
import scipy
from scipy.integrate import solve_ivp

import de_resonator as dr

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
from model import Model  # noqa: E402

BIAS, TRANSIENT, POINTS, TOL = 7450.0, 150, 50, 1e-10


def timed(job):
    started = time.perf_counter()
    out = job()
    return time.perf_counter() - started, out


def scipy_walk(model, hz, values, y0):
    """The same continuation, SciPy's: each value from the last one's final section point."""
    rows, y = [], list(y0)
    times = np.arange(TRANSIENT, TRANSIENT + POINTS) / hz
    nfev = 0
    for ac in values:
        volts = lambda s, ac=ac: BIAS + ac * np.sin(2 * np.pi * hz * s)
        out = solve_ivp(model.rhs, (0.0, times[-1]), y, method="DOP853", t_eval=times,
                        args=(volts,), rtol=TOL, atol=TOL)
        nfev += out.nfev
        rows.append(out.y[0])
        y = [out.y[0, -1], out.y[1, -1]]
    return np.array(rows), nfev


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--values", type=int, default=501)
    parser.add_argument("--scipy-values", type=int, default=501)
    args = parser.parse_args()
    device = dr.Device.reference()
    keys = device.to_dict()
    model = Model(keys)
    hz = 2 * device.frequency(BIAS)
    c = model.mass * 2 * np.pi * device.frequency(BIAS) / 100.0
    model.c = c
    values = np.linspace(0.0, 1500.0, args.values)
    rest = dr.poincare(device, BIAS, 0.0, hz, periods=1).stretch[0]
    common = dict(periods=POINTS, transient_periods=TRANSIENT, damping=c, rtol=TOL,
                  y0=(rest, 0.0))
    dr.bifurcation(device, BIAS, hz, values[:3], direction="up", **common)  # warm
    up_s, up = timed(lambda: dr.bifurcation(device, BIAS, hz, values, direction="up", **common))
    both_s, both = timed(lambda: dr.bifurcation(device, BIAS, hz, values, **common))
    n = min(args.scipy_values, args.values)
    scipy_s, (theirs, nfev) = timed(lambda: scipy_walk(model, hz, values[:n], (rest, 0.0)))
    scaled = scipy_s * args.values / n
    # A period-2 orbit's points alternate: compared as sets (each row sorted).
    apart = np.max(np.abs(np.sort(up.stretch[:n], axis=1) - np.sort(theirs, axis=1)), axis=1)
    agree = int(np.sum(apart < 1e-6))
    differ = values[:n][apart >= 1e-6]
    print(f"{args.values} values × {TRANSIENT + POINTS} periods, 2·f0 = {hz:.3f} Hz, Q 100, "
          f"rtol = atol = {TOL}; numpy {np.__version__}, SciPy {scipy.__version__}, "
          f"Python {sys.version.split()[0]}")
    print()
    print("| what | seconds | note |")
    print("|---|---|---|")
    print(f"| `dr.bifurcation`, walked up (one core) | {up_s:.3g} | "
          f"{args.values} values |")
    print(f"| `dr.bifurcation`, walked up and down (two walks, two cores) | {both_s:.3g} | "
          f"{2 * args.values} values |")
    note = "" if n == args.values else f", scaled from {n} values ({scipy_s:.3g} s)"
    print(f"| SciPy `solve_ivp` DOP853 on the equation in Python, walked up (one core) | "
          f"{scaled:.3g} | {nfev:,} right-hand sides{note}; {agree} of {n} values' section "
          f"points within 1e-6 of ours (the largest difference {apart.max():.1e}) |")
    if differ.size:
        print()
        print(f"the values whose points differ (V): {np.round(differ, 1).tolist()}")
    print()
    print(f"ours walked up: {scaled / up_s:.0f}× SciPy's time; both ways on two cores: "
          f"{2 * scaled / both_s:.0f}× SciPy's for the same work")


if __name__ == "__main__":
    main()
