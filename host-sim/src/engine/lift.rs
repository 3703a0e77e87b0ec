//! The amplifier's fast response, taken out of the plant's solve in closed form.
//!
//! After a DAC step the amplifier's output approaches its target as V = T − g·e^(−rσ)
//! (r = 2π·bandwidth, σ the time since the exponential began), so the membrane's
//! electrostatic force (model.md §4: M·λ'' = … + ε·W·λ2p²·V²·λ/H) carries
//! β·λ·φ(σ) with φ = V² − T² = −2Tg·e^(−rσ) + g²·e^(−2rσ). A solver resolving that
//! 80 µs transient to 1e-10 takes several steps a tick. Here the stretch is split as
//! λ = λ̂ + η(σ): η is a sum of polynomials times e^(−mrσ), the linear response of the
//! membrane (stiffness κ(σ), damping γ, about the slow motion ℓ(σ)) to that forcing, so
//! that λ̂ carries nothing fast but what the linearisation leaves (second order in the
//! transient's size). The change of variables is exact: the solver integrates λ̂'s own
//! equation (`plant::Motion`) under its usual error control, so the scene's accuracy is the
//! solver's; only the number of steps depends on how well η fits.

/// The powers of e^(−rσ) in a response: φ has 1 and 2.
const RATES: usize = 2;
/// Polynomial degrees up to 2: ℓ is quadratic (its cubic term changed no step of the
/// reference scene; without the linear term, twice the right-hand sides).
const DEGREES: usize = 3;

/// Σ_m Σ_j c[m][j]·σ^j·e^(−(m+1)rσ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PolyExp {
    c: [[f64; DEGREES]; RATES],
}

impl PolyExp {
    /// The particular solution η of η'' + γη' + κη = self of the same form: for each rate
    /// ρ = (m+1)r, P with P'' + (γ − 2ρ)P' + (ρ² − γρ + κ)P = Q, from the top degree down.
    fn solve(&self, rate: f64, damping: f64, stiffness: f64) -> PolyExp {
        let mut out = PolyExp::default();
        for (m, q) in self.c.iter().enumerate() {
            let rho = (m + 1) as f64 * rate;
            let inverse = 1.0 / (rho * rho - damping * rho + stiffness);
            let d1 = damping - 2.0 * rho;
            let p = &mut out.c[m];
            for j in (0..DEGREES).rev() {
                let next = if j + 1 < DEGREES { p[j + 1] } else { 0.0 };
                let after = if j + 2 < DEGREES { p[j + 2] } else { 0.0 };
                p[j] = (q[j] - d1 * (j + 1) as f64 * next - ((j + 2) * (j + 1)) as f64 * after)
                    * inverse;
            }
        }
        out
    }

    /// The coefficients of η, η' and η'' (each Σ_m Q_m(σ)·e^(−(m+1)rσ)): with ρ = (m+1)r,
    /// Q_m is P_m for η, P_m' − ρP_m for η', P_m'' − 2ρP_m' + ρ²P_m for η''.
    fn derivatives(&self, rate: f64) -> [PolyExp; 3] {
        let derivative = |q: &[f64; DEGREES]| -> [f64; DEGREES] {
            std::array::from_fn(|j| {
                if j + 1 < DEGREES {
                    (j + 1) as f64 * q[j + 1]
                } else {
                    0.0
                }
            })
        };
        let mut out = [*self; 3];
        for (m, p) in self.c.iter().enumerate() {
            let rho = (m + 1) as f64 * rate;
            let (p1, p2) = (derivative(p), derivative(&derivative(p)));
            out[1].c[m] = std::array::from_fn(|j| p1[j] - rho * p[j]);
            out[2].c[m] = std::array::from_fn(|j| p2[j] - 2.0 * rho * p1[j] + rho * rho * p[j]);
        }
        out
    }

    /// The value at σ, with `z` = e^(−rσ).
    #[inline]
    fn at(&self, sigma: f64, z: f64) -> f64 {
        let mut value = 0.0;
        for p in self.c.iter().rev() {
            let q = p.iter().rev().fold(0.0, |sum, a| sum * sigma + a);
            value = (value + q) * z;
        }
        value
    }
}

/// The membrane's slow motion at the transient's start and its linearisation there: what
/// η is the response about.
#[derive(Clone, Copy, Debug)]
pub struct Local {
    /// λ̂ and its first two time derivatives at σ = 0.
    pub taylor: [f64; 3],
    /// κ = −∂λ''/∂λ at σ = 0 (networks frozen), 1/s².
    pub stiffness: f64,
    /// γ = damping/M, 1/s.
    pub damping: f64,
}

/// The fast part of the stretch over one exponential of the amplifier.
#[derive(Clone, Copy, Debug)]
pub struct Lift {
    /// r = 2π·bandwidth, 1/s.
    pub rate: f64,
    /// T and g of the amplifier's output V = T − g·e^(−rσ), V.
    pub target_volts: f64,
    pub gap_volts: f64,
    /// η and its first two derivatives.
    pub eta: [PolyExp; 3],
}

impl Lift {
    /// η for V = T − g·e^(−rσ) (`target_volts` T, `gap_volts` g) on a membrane whose
    /// electrostatic acceleration is `beta`·λ·V² (1/(s²·V²)), about `local`: the particular
    /// solution of η'' + γη' + κη = β·φ(σ)·ℓ(σ), ℓ the quadratic of `local.taylor`. What it
    /// leaves in λ̂'s equation (β·φ·(λ̂ − ℓ + η), κ's change over the transient times η) is
    /// second order in the transient and the step; it costs the solver steps, not accuracy.
    ///
    /// `None` where η is undefined or ill-conditioned: an input not finite, or the membrane
    /// with a mode near a rate of the exponential (ρ² − γρ + κ within a hundredth of ρ²: η
    /// would be huge and λ̂ its difference from λ); the tick is then solved unlifted.
    pub fn new(
        rate: f64,
        target_volts: f64,
        gap_volts: f64,
        beta: f64,
        local: &Local,
    ) -> Option<Lift> {
        let finite = [
            rate,
            target_volts,
            gap_volts,
            beta,
            local.stiffness,
            local.damping,
        ]
        .iter()
        .chain(&local.taylor)
        .all(|x| x.is_finite());
        let conditioned = (1..=RATES).all(|m| {
            let rho = m as f64 * rate;
            (rho * rho - local.damping * rho + local.stiffness).abs() > 0.01 * rho * rho
        });
        if !(finite && conditioned && rate > 0.0) {
            return None;
        }
        let (t, g) = (target_volts, gap_volts);
        let phi = [-2.0 * t * g * beta, g * g * beta];
        let [l0, l1, l2] = local.taylor;
        let slow = [l0, l1, 0.5 * l2];
        let mut forcing = PolyExp::default();
        for (row, p) in forcing.c.iter_mut().zip(phi) {
            *row = slow.map(|l| p * l);
        }
        Some(Lift {
            rate,
            target_volts,
            gap_volts,
            eta: forcing
                .solve(rate, local.damping, local.stiffness)
                .derivatives(rate),
        })
    }

    /// (η, η', η'') and the amplifier's output V at σ.
    pub fn at(&self, sigma: f64) -> ((f64, f64, f64), f64) {
        let z = (-self.rate * sigma).exp();
        let [e0, e1, e2] = &self.eta;
        (
            (e0.at(sigma, z), e1.at(sigma, z), e2.at(sigma, z)),
            self.target_volts - self.gap_volts * z,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The particular solution satisfies its equation: η'' + γη' + κη against the forcing,
    /// both evaluated at several σ.
    #[test]
    fn the_particular_solution_satisfies_its_equation() {
        let (rate, gamma, kappa) = (12_566.0, 3.0, 7.6e4);
        let mut q = PolyExp::default();
        q.c[0] = [2.0, -5.0, 7.0];
        q.c[1] = [1.0, 3.0, -2.0];
        let [eta, first, second] = q.solve(rate, gamma, kappa).derivatives(rate);
        for sigma in [0.0, 1e-5, 8e-5, 3e-4, 1e-3] {
            let z = (-rate * sigma).exp();
            let (e0, e1, e2) = (eta.at(sigma, z), first.at(sigma, z), second.at(sigma, z));
            let f = q.at(sigma, z);
            let lhs = e2 + gamma * e1 + kappa * e0;
            assert!(
                (lhs - f).abs() <= 1e-12 * f.abs().max(1e-3),
                "{sigma}: {lhs} {f}"
            );
        }
    }

    /// (η, η', η'') agree with differences of η.
    #[test]
    fn derivatives_agree_with_differences() {
        let rate = 12_566.0;
        let mut p = PolyExp::default();
        p.c[0] = [1.0, 2e3, -3e6];
        p.c[1] = [-0.5, 1e3, 4e9];
        let d = p.derivatives(rate);
        let at = |s: f64| {
            let z = (-rate * s).exp();
            (d[0].at(s, z), d[1].at(s, z), d[2].at(s, z))
        };
        let (s, h) = (1.3e-4, 1e-8);
        let (e0, e1, e2) = at(s);
        let (up, down) = (at(s + h), at(s - h));
        assert!(((up.0 - down.0) / (2.0 * h) - e1).abs() < 1e-6 * e1.abs());
        assert!(((up.1 - down.1) / (2.0 * h) - e2).abs() < 1e-6 * e2.abs());
        assert!(e0.is_finite());
    }

    /// A membrane with a mode at the exponential's rate (an overdamped plant: ρ² − γρ + κ = 0
    /// at ρ = r), or a stiffness not finite: no lift.
    #[test]
    fn no_lift_where_it_is_undefined() {
        let rate = 12_566.0;
        let local = |stiffness: f64, damping: f64| Local {
            taylor: [2.0, 0.1, -3.0],
            stiffness,
            damping,
        };
        assert!(Lift::new(rate, 6000.0, 10.0, 1e-3, &local(7.6e4, 3.0)).is_some());
        let damping = rate + 7.6e4 / rate;
        assert!(Lift::new(rate, 6000.0, 10.0, 1e-3, &local(7.6e4, damping)).is_none());
        assert!(Lift::new(rate, 6000.0, 10.0, 1e-3, &local(f64::NAN, 3.0)).is_none());
    }
}
