"""The reference device's equations in model.md §4's dimensionless form, restated for the
peers of `scripts/bench-peers.sh` (sharing no code with the Rust core). Time τ = t/T0,
T0² = M/(μ·L2·H); Φ̄ = (Φ/H)·√(ε/μ); c̄ = c·T0/M; d²λ/dτ² = s̄1(λB) − s̄1(λ) + Φ̄²λλ2p² − c̄λ'.
"""
import math

# The reference device of model.md §9 (devices/reference.toml).
MU, JLIM, EPS = 45e3, 120.0, 4.7 * 8.8541878128e-12
RHO, H, L1A, L1B, L2, BAR = 960.0, 1.0e-3, 20e-3, 20e-3, 40e-3, 2e-3
L1P, L2P = 2.0, 2.0
MASS = BAR * L1A + RHO * L2 * H * L1A * (L1A + L1B) / 3.0
RAD_PER_S = math.sqrt(MU * L2 * H / MASS)  # 1/T0
VOLTS_PER_UNIT = H * math.sqrt(MU / EPS)


def dimensionless(bias_volts, ac_volts, drive_hz, damping):
    """(Φ̄ bias, Φ̄ AC, Ω̄ drive, c̄) for the right-hand side."""
    return (bias_volts / VOLTS_PER_UNIT, ac_volts / VOLTS_PER_UNIT,
            2.0 * math.pi * drive_hz / RAD_PER_S, damping / (MASS * RAD_PER_S))


def s1(l1):
    """Gent s̄1 at (λ1, λ2p) (model.md §3)."""
    i1 = l1 * l1 + L2P * L2P + 1.0 / (l1 * l1 * L2P * L2P)
    return (l1 - 1.0 / (l1 ** 3 * L2P * L2P)) / (1.0 - (i1 - 3.0) / JLIM)


def acceleration(stretch, bias_dimless):
    passive = ((L1A + L1B) * L1P - L1A * stretch) / L1B
    return s1(passive) - s1(stretch) + bias_dimless * bias_dimless * stretch * L2P * L2P


def equilibrium(bias_dimless):
    """The loading branch's stretch at a bias: bisection on λ'' = 0 in [λ1p, 3]."""
    low, high = L1P, 3.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if acceleration(mid, bias_dimless) > 0.0:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def ds1(l1):
    """ds̄1/dλ1 at (λ1, λ2p), by the quotient rule on s1's numerator and denominator."""
    i1 = l1 * l1 + L2P * L2P + 1.0 / (l1 * l1 * L2P * L2P)
    num = l1 - 1.0 / (l1 ** 3 * L2P * L2P)
    den = 1.0 - (i1 - 3.0) / JLIM
    dnum = 1.0 + 3.0 / (l1 ** 4 * L2P * L2P)
    dden = -(2.0 * l1 - 2.0 / (l1 ** 3 * L2P * L2P)) / JLIM
    return (dnum * den - num * dden) / (den * den)


def stiffness(stretch, bias_dimless):
    """∂λ''/∂λ at a constant voltage (the Jacobian's lower-left entry, damping apart)."""
    passive = ((L1A + L1B) * L1P - L1A * stretch) / L1B
    return -ds1(passive) * L1A / L1B - ds1(stretch) + bias_dimless * bias_dimless * L2P * L2P
