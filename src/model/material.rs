//! Ideal dielectric with Gent elasticity (model.md §3), in units of the shear modulus μ.
//!
//! Every stress and stiffness here is divided by μ, so the numbers stay near 1 in `f32`.
//! Neo-Hookean is the Gent model with `Jlim = ∞`, held as `1/Jlim = 0`.

use crate::numerics::real::Real;

/// Gent hyperelastic material, dimensionless (stresses over μ).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gent<T> {
    /// `1/Jlim`; zero for neo-Hookean.
    inv_jlim: T,
}

/// Second derivatives of the free energy over μ with respect to (λ1, λ2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hessian<T> {
    pub d11: T,
    pub d12: T,
    pub d22: T,
}

impl<T: Real> Hessian<T> {
    /// This elastic Hessian at (λ1, λ2) with the electrical energy −½·Φ̄²·λ1²·λ2² added
    /// (model.md §6.2).
    pub fn under_bias(self, l1: T, l2: T, bias_dimless_squared: T) -> Self {
        let p2 = bias_dimless_squared;
        Hessian {
            d11: self.d11 - p2 * l2 * l2,
            d12: self.d12 - T::of(2.0) * p2 * l1 * l2,
            d22: self.d22 - p2 * l1 * l1,
        }
    }

    /// Positive-definiteness margin: `min(d11, det)`, positive exactly when definite (NaN,
    /// and so failing, when either part is NaN).
    pub fn definiteness(&self) -> T {
        let det = self.d11 * self.d22 - self.d12 * self.d12;
        self.d11.min_margin(det)
    }
}

impl<T: Real> Gent<T> {
    /// Neo-Hookean (`Jlim = ∞`).
    pub fn neo_hookean() -> Self {
        Self {
            inv_jlim: T::zero(),
        }
    }

    /// Gent with the given `Jlim` (> 0; the caller validates).
    pub fn with_jlim(jlim: T) -> Self {
        Self {
            inv_jlim: T::one() / jlim,
        }
    }

    /// `1/Jlim` (zero for neo-Hookean).
    pub fn inv_jlim(&self) -> T {
        self.inv_jlim
    }

    /// First invariant `I1 = λ1² + λ2² + λ1⁻²λ2⁻²` of an incompressible membrane.
    pub fn first_invariant(l1: T, l2: T) -> T {
        l1 * l1 + l2 * l2 + T::one() / (l1 * l1 * l2 * l2)
    }

    /// Gent softening factor `1 − (I1 − 3)/Jlim` (1 for neo-Hookean).
    fn softening(&self, l1: T, l2: T) -> T {
        T::one() - (Self::first_invariant(l1, l2) - T::of(3.0)) * self.inv_jlim
    }

    /// Free energy `Ws/μ` (model.md §3).
    pub fn energy(&self, l1: T, l2: T) -> T {
        if self.inv_jlim == T::zero() {
            (Self::first_invariant(l1, l2) - T::of(3.0)) * T::of(0.5)
        } else {
            -self.softening(l1, l2).ln() / (T::of(2.0) * self.inv_jlim)
        }
    }

    /// Nominal stress `s1/μ = ∂(Ws/μ)/∂λ1` (model.md §3).
    pub fn stress_1(&self, l1: T, l2: T) -> T {
        (l1 - T::one() / (l1 * l1 * l1 * l2 * l2)) / self.softening(l1, l2)
    }

    /// `stress_1` and `lock_up_margin` at once, the invariant worked out once (the monitor's
    /// every sample: the same floats as the two apart).
    pub fn stress_1_and_lock_up(&self, l1: T, l2: T) -> (T, T) {
        let i1 = Self::first_invariant(l1, l2);
        let g = T::one() - (i1 - T::of(3.0)) * self.inv_jlim;
        (
            (l1 - T::one() / (l1 * l1 * l1 * l2 * l2)) / g,
            T::one() - i1 * self.inv_jlim,
        )
    }

    /// `s̄1(a, λ2) − s̄1(b, λ2)` without subtracting two near-equal stresses: every term
    /// carries the factor `a − b`, which the caller passes in (it can often form it exactly).
    /// Used for Φ̄²(λ), where a plain difference loses f32 digits at small bias.
    pub fn stress_1_difference(&self, a: T, b: T, a_minus_b: T, l2: T) -> T {
        let inv_l2_sq = T::one() / (l2 * l2);
        let ab = a * b;
        // h(x) = x − x⁻³λ2⁻²:  h(a) − h(b) = (a − b)·[1 + λ2⁻²·(a² + ab + b²)/(a³b³)]
        let dh = a_minus_b * (T::one() + inv_l2_sq * (a * a + ab + b * b) / (ab * ab * ab));
        let hb = b - inv_l2_sq / (b * b * b);
        self.softened_difference(a, b, a_minus_b, l2, dh, hb)
    }

    /// `s̄2(a, λ2) − s̄2(b, λ2)` (λ1 = a against λ1 = b at the same λ2), factored by `a − b`
    /// like [`Gent::stress_1_difference`]: for checks near the pre-stretch in f32.
    pub fn stress_2_difference(&self, a: T, b: T, a_minus_b: T, l2: T) -> T {
        let inv_l2_cubed = T::one() / (l2 * l2 * l2);
        let ab = a * b;
        // h(x) = λ2 − λ2⁻³x⁻²:  h(a) − h(b) = λ2⁻³·(a − b)·(a + b)/(a²b²)
        let dh = inv_l2_cubed * a_minus_b * (a + b) / (ab * ab);
        let hb = l2 - inv_l2_cubed / (b * b);
        self.softened_difference(a, b, a_minus_b, l2, dh, hb)
    }

    /// `I1(a, λ2) − I1(b, λ2) = (a − b)·(a + b)·(1 − λ2⁻²/(a²b²))`, factored by `a − b`.
    pub fn first_invariant_difference(a: T, b: T, a_minus_b: T, l2: T) -> T {
        let ab = a * b;
        a_minus_b * (a + b) * (T::one() - T::one() / (l2 * l2 * ab * ab))
    }

    /// `h(a)/g(a) − h(b)/g(b)` from `dh = h(a) − h(b)` and `h(b)`, with the Gent factor
    /// g = 1 − (I1 − 3)/Jlim: `[dh·g(b) + h(b)·(I1(a) − I1(b))/Jlim]/(g(a)·g(b))`.
    fn softened_difference(&self, a: T, b: T, a_minus_b: T, l2: T, dh: T, hb: T) -> T {
        if self.inv_jlim == T::zero() {
            return dh;
        }
        let di1 = Self::first_invariant_difference(a, b, a_minus_b, l2);
        let (ga, gb) = (self.softening(a, l2), self.softening(b, l2));
        (dh * gb + hb * di1 * self.inv_jlim) / (ga * gb)
    }

    /// Nominal stress `s2/μ = ∂(Ws/μ)/∂λ2` (model.md §3).
    pub fn stress_2(&self, l1: T, l2: T) -> T {
        self.stress_1(l2, l1)
    }

    /// Hessian of `Ws/μ` in (λ1, λ2): `∂²I1/2g + (∂I1)(∂I1)/(2·Jlim·g²)`.
    pub fn hessian(&self, l1: T, l2: T) -> Hessian<T> {
        self.hessian_with(l1, l2, self.stiffness_1(l1, l2))
    }

    /// `hessian` with its d11, `stiffness_1(l1, l2)`, already worked out.
    pub fn hessian_with(&self, l1: T, l2: T, d11: T) -> Hessian<T> {
        let g = self.softening(l1, l2);
        let inv_l1 = T::one() / l1;
        let inv_l2 = T::one() / l2;
        let c = inv_l1 * inv_l1 * inv_l2 * inv_l2; // λ1⁻²λ2⁻²
                                                   // Half-derivatives of I1: ∂I1/∂λi / 2.
        let h1 = l1 - c * inv_l1;
        let h2 = l2 - c * inv_l2;
        let lock = T::of(2.0) * self.inv_jlim / (g * g);
        Hessian {
            d11,
            d12: T::of(2.0) * c * inv_l1 * inv_l2 / g + lock * h1 * h2,
            d22: (T::one() + T::of(3.0) * c * inv_l2 * inv_l2) / g + lock * h2 * h2,
        }
    }

    /// Hessian of the free energy under voltage control, `F/μ = Ws/μ − ½·Φ̄²·λ1²·λ2²`
    /// (model.md §6.2), with Φ̄ = (Φ/H)·√(ε/μ).
    pub fn hessian_under_bias(&self, l1: T, l2: T, bias_dimless_squared: T) -> Hessian<T> {
        self.hessian(l1, l2)
            .under_bias(l1, l2, bias_dimless_squared)
    }

    /// Stiffness `s1'/μ = ∂²(Ws/μ)/∂λ1²`.
    pub fn stiffness_1(&self, l1: T, l2: T) -> T {
        // d11 of `hessian` alone: it is on the hot paths (every frequency, every Newton step).
        let g = self.softening(l1, l2);
        let inv_l1_sq = T::one() / (l1 * l1);
        let c = inv_l1_sq / (l2 * l2); // λ1⁻²λ2⁻²
        let h1 = l1 - c / l1;
        (T::one() + T::of(3.0) * c * inv_l1_sq) / g + T::of(2.0) * self.inv_jlim * h1 * h1 / (g * g)
    }

    /// Stretch-limit margin `1 − I1/Jlim`: the check `I1 < Jlim` of model.md §6.6
    /// (always 1 for neo-Hookean).
    pub fn lock_up_margin(&self, l1: T, l2: T) -> T {
        T::one() - Self::first_invariant(l1, l2) * self.inv_jlim
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factored difference is the plain difference where the plain one is accurate.
    #[test]
    fn stress_difference_matches_plain_subtraction() {
        for material in [Gent::neo_hookean(), Gent::with_jlim(30.0)] {
            for (a, b, l2) in [(2.5, 1.5, 2.0), (1.2, 0.8, 3.0), (3.0, 2.9, 1.1)] {
                let plain = material.stress_1(a, l2) - material.stress_1(b, l2);
                let factored = material.stress_1_difference(a, b, a - b, l2);
                assert!(
                    (plain - factored).abs() < 1e-13 * plain.abs(),
                    "{a} {b} {l2}"
                );
            }
        }
    }

    /// At small bias (a − b ≪ a) the f32 factored difference keeps its digits: checked
    /// against the f64 plain difference, which still has ~9 digits there.
    #[test]
    fn stress_difference_in_f32_at_small_separation() {
        for jlim in [None, Some(30.0)] {
            let (m32, m64) = match jlim {
                None => (Gent::<f32>::neo_hookean(), Gent::<f64>::neo_hookean()),
                Some(j) => (Gent::with_jlim(j as f32), Gent::with_jlim(j)),
            };
            let (a, d, l2) = (2.0f64, 1e-4f64, 2.0f64);
            let exact = m64.stress_1(a + d, l2) - m64.stress_1(a - d, l2);
            let f32_value = m32.stress_1_difference((a + d) as f32, (a - d) as f32, 2e-4, 2.0);
            let plain_f32 = m32.stress_1((a + d) as f32, 2.0) - m32.stress_1((a - d) as f32, 2.0);
            let err = (f64::from(f32_value) - exact).abs() / exact;
            let plain_err = (f64::from(plain_f32) - exact).abs() / exact;
            assert!(err < 1e-6, "{err}");
            assert!(
                plain_err > 10.0 * err,
                "plain {plain_err} vs factored {err}"
            );
        }
    }
}
