//! Equilibrium on the loading branch and small oscillation about it (model.md §5).
//!
//! The branch is parametrised by the stretch λ = λ1A: the bias is explicit in λ,
//! Φ(λ) = H·√((s1(λ) − s1(λB))/(ε·λ·λ2p²)). These are the raw physics, defined beyond the
//! safe region too; `safety` decides where they may be used.

use crate::model::device::Device;
use crate::numerics::real::Real;
use crate::numerics::roots::root;

/// An equilibrium on the loading branch, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Equilibrium<T> {
    /// λ = λ1A.
    pub stretch: T,
    /// δ = λ − λ1p, held apart from `stretch`: near the pre-stretch f32 resolves δ far
    /// finer than λ itself, and the bias (Φ ∝ √δ there) needs that resolution.
    pub offset: T,
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
    /// λB = (L1·λ1p − L1A·λ)/L1B, the passive membrane's stretch (model.md §2).
    pub fn passive_stretch(&self, stretch: T) -> T {
        // Written so that λ = λ1p gives λB = λ1p exactly (and Φ = 0, not a rounding NaN).
        self.prestretch_1() + self.length_ratio() * (self.prestretch_1() - stretch)
    }

    /// Φ̄² = (s̄1(λ) − s̄1(λB))/(λ·λ2p²): the squared dimensionless bias that holds λ.
    pub fn bias_dimless_squared(&self, stretch: T) -> T {
        self.bias_dimless_squared_at(stretch - self.prestretch_1())
    }

    /// Φ̄² at the offset δ = λ − λ1p on the branch. The stress difference is taken factored,
    /// with λ − λB = (1 + L1A/L1B)·δ exact, so Φ̄² keeps its digits at small bias.
    pub fn bias_dimless_squared_at(&self, offset: T) -> T {
        let l2p = self.prestretch_2();
        let l1p = self.prestretch_1();
        let stretch = l1p + offset;
        let passive = l1p - self.length_ratio() * offset;
        let apart = (T::one() + self.length_ratio()) * offset;
        let difference = self
            .material()
            .stress_1_difference(stretch, passive, apart, l2p);
        difference / (stretch * l2p * l2p)
    }

    /// Φ(λ), V, on the loading branch (NaN beyond a fold, where no bias holds λ).
    pub fn bias_volts(&self, stretch: T) -> T {
        self.bias_volts_at(stretch - self.prestretch_1())
    }

    /// Φ, V, at the offset δ = λ − λ1p on the loading branch.
    pub fn bias_volts_at(&self, offset: T) -> T {
        self.bias_dimless_squared_at(offset).sqrt() * self.volts_per_unit()
    }

    /// Dimensionless ω² = s̄1'(λ) + (L1A/L1B)·s̄1'(λB) − Φ̄²·λ2p² at stretch λ under Φ̄²
    /// (model.md §5): the local stiffness, also away from equilibrium.
    pub fn stiffness_dimless(&self, stretch: T, bias_dimless_squared: T) -> T {
        let l2p = self.prestretch_2();
        self.elastic_stiffness_dimless(stretch) - bias_dimless_squared * l2p * l2p
    }

    /// The elastic part of `stiffness_dimless`: s̄1'(λ) + (L1A/L1B)·s̄1'(λB).
    pub fn elastic_stiffness_dimless(&self, stretch: T) -> T {
        let m = self.material();
        let l2p = self.prestretch_2();
        m.stiffness_1(stretch, l2p)
            + self.length_ratio() * m.stiffness_1(self.passive_stretch(stretch), l2p)
    }

    /// ω², rad²/s², of small oscillation about the equilibrium at stretch λ.
    pub fn omega_squared(&self, stretch: T) -> T {
        let w = self.rad_per_s_per_unit();
        self.stiffness_dimless(stretch, self.bias_dimless_squared(stretch)) * w * w
    }

    /// f = ω/2π, Hz, about the equilibrium at λ; zero where ω² ≤ 0 (at or past a fold).
    pub fn natural_frequency_hz(&self, stretch: T) -> T {
        self.natural_frequency_hz_at(stretch - self.prestretch_1())
    }

    /// f, Hz, about the equilibrium at the offset δ = λ − λ1p; zero where ω² ≤ 0.
    pub fn natural_frequency_hz_at(&self, offset: T) -> T {
        let stretch = self.prestretch_1() + offset;
        let w2 = self.stiffness_dimless(stretch, self.bias_dimless_squared_at(offset));
        if w2 > T::zero() {
            w2.sqrt() * self.rad_per_s_per_unit() / two_pi()
        } else {
            T::zero()
        }
    }

    /// The equilibrium at stretch λ on the loading branch.
    pub fn equilibrium(&self, stretch: T) -> Equilibrium<T> {
        self.equilibrium_at(stretch - self.prestretch_1())
    }

    /// The stretch λ1p + δ, rounded toward the pre-stretch: the largest stretch λ with
    /// λ − λ1p ≤ δ, so that a stretch reported for an offset never lies past it.
    pub fn stretch_at(&self, offset: T) -> T {
        let l1p = self.prestretch_1();
        let mut stretch = l1p + offset;
        // At most two steps: λ1p + δ is rounded to nearest.
        for _ in 0..2 {
            if stretch - l1p > offset {
                stretch = stretch.next_down();
            }
        }
        stretch
    }

    /// The equilibrium at the offset δ = λ − λ1p on the loading branch.
    pub fn equilibrium_at(&self, offset: T) -> Equilibrium<T> {
        Equilibrium {
            stretch: self.stretch_at(offset),
            offset,
            volts: self.bias_volts_at(offset),
            natural_frequency_hz: self.natural_frequency_hz_at(offset),
        }
    }

    /// The stretch on the loading branch held by `volts` (sign ignored), searched in
    /// `[λ1p, max_stretch]` where Φ(λ) rises: the largest stretch whose bias does not exceed
    /// `volts` (to one unit in the last place). `None` if `volts` is NaN or above Φ(max_stretch).
    pub fn stretch_for_bias(&self, volts: T, max_stretch: T) -> Option<T> {
        self.offset_for_bias(volts, max_stretch - self.prestretch_1())
            .map(|offset| self.stretch_at(offset))
    }

    /// As [`Device::stretch_for_bias`], in the offset δ = λ − λ1p (searched in
    /// `[0, max_offset]`), which f32 resolves finely near the pre-stretch.
    pub fn offset_for_bias(&self, volts: T, max_offset: T) -> Option<T> {
        // Compared as `bias_volts_at` computes them, so Φ(max_offset) itself is accepted.
        let volts = volts.abs();
        if !(volts <= self.bias_volts_at(max_offset)) {
            return None;
        }
        if !(max_offset > T::zero()) || volts == T::zero() {
            return Some(T::zero());
        }
        let (below, _) = root(T::zero(), max_offset, |d| self.bias_volts_at(d) - volts);
        Some(below)
    }
}
