#!/usr/bin/env python3
"""numbalsoda's DOP853 (Hairer's code in C++, right-hand side compiled by numba) on the scene
`host-sim simulate` runs, in-process, the JIT excluded (one warm-up solve first).

Usage: numbalsoda_scene.py BIAS_V AC_V DRIVE_HZ DURATION_S STEP_S TOLERANCE RUNS
Prints one JSON object: the final stretch, the best and mean solve time, s.
"""
import json
import sys
import time

import numba as nb
import numpy as np
from numbalsoda import dop853

import scene

bias, ac, hz, duration, step, tol = map(float, sys.argv[1:7])
runs = int(sys.argv[7])
pb, pa, omega, damping = scene.dimensionless(bias, ac, hz, 0.0)
L1, L2P, JLIM, L1A, L1B, L1P = scene.L1A + scene.L1B, scene.L2P, scene.JLIM, scene.L1A, scene.L1B, scene.L1P


@nb.cfunc("void(double, CPointer(double), CPointer(double), CPointer(double))")
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


# The output times as host-sim's: every step from 0, the last at the duration exactly.
scale = scene.RAD_PER_S
count = int(np.ceil(duration / step * (1.0 - 1e-12)))
tau = np.append(np.arange(count) * step * scale, duration * scale)
y0 = np.array([scene.equilibrium(pb), 0.0])
data = np.array([pb, pa, omega, damping])
usol, ok = dop853(rhs.address, y0, tau, data=data, rtol=tol, atol=tol)  # warm-up (JIT)
times = []
for _ in range(runs):
    t0 = time.perf_counter()
    usol, ok = dop853(rhs.address, y0, tau, data=data, rtol=tol, atol=tol)
    times.append(time.perf_counter() - t0)
if not ok:
    sys.exit("numbalsoda's dop853 failed")
print(json.dumps({"final_stretch": usol[-1, 0], "samples": len(tau),
                  "best_seconds": min(times), "mean_seconds": sum(times) / len(times)}))
