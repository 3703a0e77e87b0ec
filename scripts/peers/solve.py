#!/usr/bin/env python3
"""One peer's solve of a scene, for the work-precision study (scripts/peers/work_precision.py):
SciPy's DOP853, Radau or LSODA (`solve_ivp`, the analytic Jacobian for the implicit ones), or
numbalsoda's DOP853 (Hairer's code in C++, the right-hand side compiled by numba and cached
on disk), on the reference device's equations as scene.py restates them.

Usage: solve.py [--runs N] SOLVER BIAS_V AC_V DRIVE_HZ DAMPING_NS DURATION_S STEP_S START
                TOLERANCE [SERIES]
  SOLVER     scipy-DOP853 | scipy-Radau | scipy-LSODA | numbalsoda-dop853
  START      equilibrium (the bias's equilibrium, at rest) | prestretch (λ1p, at rest)
  SERIES     a file to write the stretch at every output time to (float64, raw)
  --runs N   solve N times in this process (default 1)
Output times as host-sim's: every STEP_S from 0, the last at the duration exactly; rtol = atol
= TOLERANCE on the dimensionless state. Prints one JSON object: the final stretch, the solve's
time in this process (s, the median of the runs; their best and mean; numbalsoda's JIT
excluded by a first solve), the right-hand side's evaluations where the solver counts them.
"""
import functools
import json
import math
import sys
import time

import numpy as np

import scene

SOLVERS = ("scipy-DOP853", "scipy-Radau", "scipy-LSODA", "numbalsoda-dop853")


def main(argv):
    runs = 1
    if argv[:1] == ["--runs"] and len(argv) > 1 and argv[1].isdigit() and int(argv[1]) > 0:
        runs, argv = int(argv[1]), argv[2:]
    if len(argv) not in (9, 10) or argv[0] not in SOLVERS:
        sys.exit(__doc__)
    solver = argv[0]
    bias, ac, hz, damping, duration, step = map(float, argv[1:7])
    start, tol = argv[7], float(argv[8])
    pb, pa, omega, c = scene.dimensionless(bias, ac, hz, damping)
    y0 = np.array([scene.equilibrium(pb) if start == "equilibrium" else scene.L1P, 0.0])
    count = int(math.ceil(duration / step * (1.0 - 1e-12)))
    tau = np.append(np.arange(count) * step * scene.RAD_PER_S, duration * scene.RAD_PER_S)
    solve = numbalsoda if solver == "numbalsoda-dop853" else scipy(solver.split("-")[1])
    times = []
    for _ in range(runs):
        stretch, seconds, evaluations = solve(y0, tau, (pb, pa, omega, c), tol)
        times.append(seconds)
    if len(argv) == 10:
        stretch.astype(np.float64).tofile(argv[9])
    print(json.dumps({"solver": solver, "final_stretch": float(stretch[-1]),
                      "samples": len(tau), "solve_seconds": float(np.median(times)),
                      "best_seconds": min(times), "mean_seconds": sum(times) / runs,
                      "evaluations": evaluations}))


def scipy(method):
    """SciPy's `method` as a solve of (y0, tau, drive, tol)."""
    from scipy.integrate import solve_ivp

    return lambda y0, tau, drive, tol: scipy_solve(solve_ivp, method, y0, tau, drive, tol)


def scipy_solve(solve_ivp, method, y0, tau, drive, tol):
    pb, pa, omega, c = drive

    def rhs(t, y):
        volts = pb + pa * math.sin(omega * t)
        return [y[1], scene.acceleration(y[0], volts) - c * y[1]]

    def jac(t, y):
        volts = pb + pa * math.sin(omega * t)
        return [[0.0, 1.0], [scene.stiffness(y[0], volts), -c]]

    extra = {} if method == "DOP853" else {"jac": jac}
    started = time.perf_counter()
    sol = solve_ivp(rhs, (tau[0], tau[-1]), y0, method=method, t_eval=tau, rtol=tol, atol=tol,
                    **extra)
    seconds = time.perf_counter() - started
    if not sol.success:
        sys.exit(f"SciPy's {method} failed: {sol.message}")
    return sol.y[0], seconds, int(sol.nfev)


def numbalsoda(y0, tau, drive, tol):
    rhs, dop853 = numbalsoda_rhs()
    data = np.array(drive, dtype=np.float64)
    dop853(rhs.address, y0, tau[:2], data=data, rtol=tol, atol=tol)  # warm-up (JIT)
    started = time.perf_counter()
    usol, ok = dop853(rhs.address, y0, tau, data=data, rtol=tol, atol=tol)
    seconds = time.perf_counter() - started
    if not ok:
        sys.exit("numbalsoda's dop853 failed")
    return usol[:, 0], seconds, None


@functools.cache
def numbalsoda_rhs():
    """The right-hand side compiled by numba (cached on disk), and numbalsoda's dop853."""
    import numba as nb
    from numbalsoda import dop853

    L1, L2P, JLIM = scene.L1A + scene.L1B, scene.L2P, scene.JLIM
    L1A, L1B, L1P = scene.L1A, scene.L1B, scene.L1P

    @nb.cfunc("void(double, CPointer(double), CPointer(double), CPointer(double))", cache=True)
    def rhs(t, y, dy, p):
        stretch = y[0]
        passive = (L1 * L1P - L1A * stretch) / L1B
        i1a = stretch * stretch + L2P * L2P + 1.0 / (stretch * stretch * L2P * L2P)
        i1b = passive * passive + L2P * L2P + 1.0 / (passive * passive * L2P * L2P)
        sa = (stretch - 1.0 / (stretch ** 3 * L2P * L2P)) / (1.0 - (i1a - 3.0) / JLIM)
        sb = (passive - 1.0 / (passive ** 3 * L2P * L2P)) / (1.0 - (i1b - 3.0) / JLIM)
        volts = p[0] + p[1] * np.sin(p[2] * t)
        dy[0] = y[1]
        dy[1] = sb - sa + volts * volts * stretch * L2P * L2P - p[3] * y[1]

    return rhs, dop853


if __name__ == "__main__":
    main(sys.argv[1:])
