#!/usr/bin/env python3
"""One scene of the reference device, solved with SciPy's solve_ivp (DOP853): the comparison
side of `scripts/bench-scipy.sh`. The equations are restated here from model.md §§2-4 in
plain SI, sharing no code with the Rust core.

Usage: scipy_scene.py BIAS_V AC_V DRIVE_HZ DURATION_S TOLERANCE
Prints one JSON object: the final stretch and velocity (1/s), and the equilibrium stretch.
"""
import json
import math
import sys

from scipy.integrate import solve_ivp
from scipy.optimize import brentq

# The reference device of model.md §9 (devices/reference.toml).
MU, JLIM, EPS = 45e3, 120.0, 4.7 * 8.8541878128e-12
RHO, H, L1A, L1B, L2, BAR = 960.0, 1.0e-3, 20e-3, 20e-3, 40e-3, 2e-3
L1P, L2P = 2.0, 2.0
L1 = L1A + L1B
MASS = BAR * L1A + RHO * L2 * H * L1A * L1 / 3.0


def s1(l1, l2):
    """Gent nominal stress in direction 1, Pa (model.md §3)."""
    i1 = l1 * l1 + l2 * l2 + 1.0 / (l1 * l1 * l2 * l2)
    return MU * (l1 - l1**-3 * l2**-2) / (1.0 - (i1 - 3.0) / JLIM)


def acceleration(stretch, volts):
    """λ'' of model.md §4 without damping, 1/s²."""
    passive = (L1 * L1P - L1A * stretch) / L1B
    field = volts / H
    return L2 * H * (s1(passive, L2P) - s1(stretch, L2P)
                     + EPS * field * field * stretch * L2P * L2P) / MASS


def main():
    bias, ac, drive_hz, duration, tol = map(float, sys.argv[1:6])
    start = brentq(lambda s: acceleration(s, bias), L1P, 3.0, xtol=1e-15, rtol=1e-15)
    omega = 2.0 * math.pi * drive_hz

    def rhs(t, y):
        return [y[1], acceleration(y[0], bias + ac * math.sin(omega * t))]

    sol = solve_ivp(rhs, (0.0, duration), [start, 0.0], method="DOP853", rtol=tol, atol=tol)
    if not sol.success:
        sys.exit(f"solve_ivp failed: {sol.message}")
    print(json.dumps({"final": {"stretch": sol.y[0, -1], "velocity": sol.y[1, -1]},
                      "start": start, "evaluations": int(sol.nfev)}))


if __name__ == "__main__":
    main()
