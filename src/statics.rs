//! Equilibrium on the loading branch and small oscillation about it (MODEL.md §5).
//!
//! The branch is parametrised by the stretch λ = λ1A: the bias is explicit in λ,
//! Φ(λ) = H·√((s1(λ) − s1(λB))/(ε·λ·λ2p²)). These are the raw physics, defined beyond the
//! safe region too; `safety` decides where they may be used.

use crate::device::Device;
use crate::real::Real;
use crate::roots::bisect;

/// An equilibrium on the loading branch, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Equilibrium<T> {
    /// λ = λ1A.
    pub stretch: T,
    /// Φ, V.
    pub volts: T,
    /// f = ω/2π, Hz.
    pub natural_frequency_hz: T,
}

/// 2π.
fn two_pi<T: Real>() -> T {
    T::of(core::f64::consts::TAU)
}

impl<T: Real> Device<T> {
    /// λB = (L1·λ1p − L1A·λ)/L1B, the passive membrane's stretch (MODEL.md §2).
    pub fn passive_stretch(&self, stretch: T) -> T {
        // Written so that λ = λ1p gives λB = λ1p exactly (and Φ = 0, not a rounding NaN).
        self.prestretch_1() + self.length_ratio() * (self.prestretch_1() - stretch)
    }

    /// Φ̄² = (s̄1(λ) − s̄1(λB))/(λ·λ2p²): the squared dimensionless bias that holds λ.
    /// The stress difference is taken factored, with λ − λB = (1 + L1A/L1B)·(λ − λ1p).
    pub fn bias_dimless_squared(&self, stretch: T) -> T {
        let l2p = self.prestretch_2();
        let apart = (T::one() + self.length_ratio()) * (stretch - self.prestretch_1());
        let difference =
            self.material()
                .stress_1_difference(stretch, self.passive_stretch(stretch), apart, l2p);
        difference / (stretch * l2p * l2p)
    }

    /// Φ(λ), V, on the loading branch (NaN beyond a fold, where no bias holds λ).
    pub fn bias_volts(&self, stretch: T) -> T {
        self.bias_dimless_squared(stretch).sqrt() * self.volts_per_unit()
    }

    /// Dimensionless ω² = s̄1'(λ) + (L1A/L1B)·s̄1'(λB) − Φ̄²·λ2p² at stretch λ under Φ̄²
    /// (MODEL.md §5): the local stiffness, also away from equilibrium.
    pub fn stiffness_dimless(&self, stretch: T, bias_dimless_squared: T) -> T {
        let m = self.material();
        let l2p = self.prestretch_2();
        m.stiffness_1(stretch, l2p)
            + self.length_ratio() * m.stiffness_1(self.passive_stretch(stretch), l2p)
            - bias_dimless_squared * l2p * l2p
    }

    /// ω², rad²/s², of small oscillation about the equilibrium at stretch λ.
    pub fn omega_squared(&self, stretch: T) -> T {
        let w = self.rad_per_s_per_unit();
        self.stiffness_dimless(stretch, self.bias_dimless_squared(stretch)) * w * w
    }

    /// f = ω/2π, Hz, about the equilibrium at λ; zero where ω² ≤ 0 (at or past a fold).
    pub fn natural_frequency_hz(&self, stretch: T) -> T {
        let w2 = self.stiffness_dimless(stretch, self.bias_dimless_squared(stretch));
        if w2 > T::zero() {
            w2.sqrt() * self.rad_per_s_per_unit() / two_pi()
        } else {
            T::zero()
        }
    }

    /// The equilibrium at stretch λ on the loading branch.
    pub fn equilibrium(&self, stretch: T) -> Equilibrium<T> {
        Equilibrium {
            stretch,
            volts: self.bias_volts(stretch),
            natural_frequency_hz: self.natural_frequency_hz(stretch),
        }
    }

    /// The stretch on the loading branch held by `volts` (sign ignored), searched in
    /// `[λ1p, max_stretch]` where Φ(λ) rises: the largest stretch whose bias does not exceed
    /// `volts` (to one unit in the last place). `None` if `volts` is NaN or above Φ(max_stretch).
    pub fn stretch_for_bias(&self, volts: T, max_stretch: T) -> Option<T> {
        // Compared as `bias_volts` computes them, so Φ(max_stretch) itself is accepted.
        let volts = volts.abs();
        let start = self.prestretch_1();
        if !(volts <= self.bias_volts(max_stretch)) {
            return None;
        }
        if !(max_stretch > start) || volts == T::zero() {
            return Some(start);
        }
        let (below, _) = bisect(start, max_stretch, |l| self.bias_volts(l) < volts);
        Some(below)
    }
}
