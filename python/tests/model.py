"""The model of docs/model.md §§2–5, written again here in numpy from the equations: the
tests' independent values (never the package's own output)."""

import numpy as np
from scipy.optimize import brentq

EPS0 = 8.8541878128e-12


class Model:
    """Statics and motion of a device from its keys (SI units, the device file's)."""

    def __init__(self, keys):
        self.mu = keys["shear_modulus"]
        self.jlim = keys.get("jlim")  # None: neo-Hookean
        self.eps = keys["relative_permittivity"] * EPS0
        self.rho = keys["density"]
        self.h = keys["thickness"]
        self.l1a = keys["length_active"]
        self.l1b = keys["length_passive"]
        self.l2 = keys["width"]
        self.m = keys["bar_mass"]
        self.l1p = keys["prestretch_1"]
        self.l2p = keys["prestretch_2"]
        self.c = keys.get("damping", 0.0)
        self.l1 = self.l1a + self.l1b
        # §4: the bars and both membranes' own inertia.
        self.mass = self.m * self.l1a + self.rho * self.l2 * self.h * self.l1a * self.l1 / 3.0

    def passive(self, lam):
        """§2: B's stretch along 1."""
        return (self.l1 * self.l1p - self.l1a * lam) / self.l1b

    def gent(self, l1, l2):
        """§3: 1 − (I1 − 3)/Jlim (1 for neo-Hookean)."""
        if self.jlim is None:
            return 1.0
        i1 = l1**2 + l2**2 + l1**-2 * l2**-2
        return 1.0 - (i1 - 3.0) / self.jlim

    def s1(self, l1, l2):
        """§3: the nominal stress along 1, Pa."""
        return self.mu * (l1 - l1**-3 * l2**-2) / self.gent(l1, l2)

    def ds1(self, l1, l2):
        """∂s1/∂λ1, differentiated by hand from §3."""
        a = l1 - l1**-3 * l2**-2
        da = 1.0 + 3.0 * l1**-4 * l2**-2
        if self.jlim is None:
            return self.mu * da
        g = self.gent(l1, l2)
        return self.mu * (da / g + 2.0 * a * a / (self.jlim * g * g))

    def bias_volts(self, lam):
        """§5: the voltage that holds stretch λ at rest."""
        num = self.s1(lam, self.l2p) - self.s1(self.passive(lam), self.l2p)
        # At λ1p the difference is 0 up to rounding, either sign.
        return self.h * np.sqrt(np.maximum(num, 0.0) / (self.eps * lam * self.l2p**2))

    def omega_squared(self, lam):
        """§5: ω² at the equilibrium of stretch λ."""
        phi = self.bias_volts(lam)
        k = (
            self.ds1(lam, self.l2p)
            + (self.l1a / self.l1b) * self.ds1(self.passive(lam), self.l2p)
            - self.eps * (phi / self.h) ** 2 * self.l2p**2
        )
        return self.l2 * self.h * k / self.mass

    def frequency_hz(self, lam):
        return np.sqrt(self.omega_squared(lam)) / (2 * np.pi)

    def rhs(self, t, y, volts):
        """§4: (λ', λ'') under Φ(t) = volts(t), in SI time."""
        lam, rate = y
        phi = volts(t)
        force = self.l2 * self.h * (
            self.s1(self.passive(lam), self.l2p)
            - self.s1(lam, self.l2p)
            + self.eps * (phi / self.h) ** 2 * lam * self.l2p**2
        )
        return [rate, (force - self.c * rate) / self.mass]

    def stretch_for_bias(self, volts, top):
        """§5: the loading branch's stretch that `volts` holds, by brentq between λ1p and
        `top` (a stretch past it on the branch)."""
        return brentq(lambda x: self.bias_volts(x) - volts, self.l1p, top, xtol=1e-15)

    def emi_hessian_positive(self, lam, d=1e-4, volts=None):
        """§6.2: the Hessian of Ws − ½ε(Φ/H)²λ1²λ2² at (λ, λ2p) positive definite, Φ the
        static bias at λ unless `volts` is given."""
        e2 = ((self.bias_volts(lam) if volts is None else volts) / self.h) ** 2

        def free(a, b):
            if self.jlim is None:
                ws = self.mu / 2 * (a**2 + b**2 + a**-2 * b**-2 - 3)
            else:
                ws = -self.mu * self.jlim / 2 * np.log(self.gent(a, b))
            return ws - 0.5 * self.eps * e2 * a**2 * b**2

        a, b = lam, self.l2p
        faa = (free(a + d, b) - 2 * free(a, b) + free(a - d, b)) / d**2
        fbb = (free(a, b + d) - 2 * free(a, b) + free(a, b - d)) / d**2
        fab = (
            free(a + d, b + d) - free(a + d, b - d) - free(a - d, b + d) + free(a - d, b - d)
        ) / (4 * d**2)
        return faa > 0 and faa * fbb - fab**2 > 0
