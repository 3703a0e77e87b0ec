//! The safe region: the six failure checks of model.md §6 and the limit of the loading branch.

pub use super::failure::FailureMode;
use crate::model::device::Device;
use crate::model::material::{Gent, Hessian};
use crate::model::statics::Equilibrium;
use crate::numerics::real::Real;
use crate::numerics::roots::bisect;

/// How far a state is from each failure: each value is positive exactly when its check holds.
/// Dimensionless (stresses over μ, fields over √(μ/ε)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Margins<T> {
    /// One value per mode, in the order of [`FailureMode::ALL`].
    pub values: [T; 7],
}

impl<T: Real> Margins<T> {
    /// The first check (in model.md order) that fails; NaN counts as a failure.
    pub fn first_failure(&self) -> Option<FailureMode> {
        FailureMode::ALL
            .into_iter()
            .zip(self.values)
            .find(|(_, v)| !(*v > T::zero()))
            .map(|(mode, _)| mode)
    }

    /// The margin of one check.
    pub fn of(&self, mode: FailureMode) -> T {
        self.values
            .get(mode as usize)
            .copied()
            .unwrap_or(T::of(f64::NAN))
    }

    /// A state outside the model: loss of tension 1 at −1, every other margin undefined.
    pub fn outside_model() -> Self {
        let mut values = [T::of(f64::NAN); 7];
        if let Some(tension) = values.get_mut(FailureMode::LossOfTension1 as usize) {
            *tension = -T::one();
        }
        Self { values }
    }
}

/// The checks of model.md §6 at one stretch without the bias: what a second device that
/// differs only in μ (the trim's estimate beside the device flashed) shares with the first,
/// so that its checks cost a few products, not the stresses again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchTerms<T> {
    in_model: bool,
    stretch: T,
    prestretch_2: T,
    /// The elastic stiffness (`Device::elastic_stiffness_dimless`).
    stiffness: T,
    /// The elastic Hessian of A (model.md §6.2).
    hessian: Hessian<T>,
    tension_1b: T,
    stress_1a: T,
    /// λ2p·s̄2 of A and of B.
    tension_2a: T,
    tension_2b: T,
    lock_up: T,
}

impl<T: Real> StretchTerms<T> {
    /// The margins under the dimensionless bias Φ̄² for a device whose breakdown field over
    /// √(μ/ε) is `breakdown_field_dimless` (see `Device::margins`).
    pub fn margins(&self, bias_dimless_squared: T, breakdown_field_dimless: T) -> Margins<T> {
        if !self.in_model {
            return Margins::outside_model();
        }
        let p2 = bias_dimless_squared;
        // §6.5: E/√(μ/ε) = Φ̄·λ·λ2p (a negative Φ̄² gives NaN, which fails).
        let field = p2.sqrt() * self.stretch * self.prestretch_2;
        let field_squared = p2 * (self.stretch * self.prestretch_2).squared();
        self.with_breakdown(p2, field_squared, breakdown_field_dimless - field)
    }

    /// The first check that fails under Φ̄² (see `Device::first_failure`): `margins`' signs,
    /// the breakdown's as Ē_B² − Ē² (no square root: the monitor's every tick).
    pub fn first_failure(
        &self,
        bias_dimless_squared: T,
        breakdown_field_dimless: T,
    ) -> Option<FailureMode> {
        if !self.in_model {
            return Some(FailureMode::LossOfTension1);
        }
        let p2 = bias_dimless_squared;
        let b = breakdown_field_dimless;
        let field_squared = p2 * (self.stretch * self.prestretch_2).squared();
        let breakdown = if b > T::zero() && p2 >= T::zero() {
            b * b - field_squared
        } else {
            T::of(f64::NAN)
        };
        self.with_breakdown(p2, field_squared, breakdown)
            .first_failure()
    }

    /// Whether every check passes for two devices that share these terms (they differ only
    /// in μ), under Φ̄² = `larger` and `smaller` (`larger` ≥ `smaller`) with their breakdown
    /// fields: all of `larger`'s checks, and `smaller`'s two that are not monotone in Φ̄²
    /// (the Hessian under bias: its bias term is indefinite; the breakdown, whose field
    /// moves with μ too). Every other margin is a term less Φ̄² times a positive factor,
    /// monotone in f32 as in exact arithmetic: passing at `larger` it passes at `smaller`.
    /// One device's checks and a few products, where both would be two (the tick's budget).
    pub fn both_pass(
        &self,
        (larger, larger_breakdown): (T, T),
        (smaller, smaller_breakdown): (T, T),
    ) -> bool {
        if !(larger >= smaller) || self.first_failure(larger, larger_breakdown).is_some() {
            return false;
        }
        let (l, l2p) = (self.stretch, self.prestretch_2);
        let field_squared = smaller * (l * l2p).squared();
        let b = smaller_breakdown;
        let breakdown = b > T::zero() && smaller >= T::zero() && b * b - field_squared > T::zero();
        breakdown && self.hessian.under_bias(l, l2p, smaller).definiteness() > T::zero()
    }

    /// The first of the checks no bias enters that fails here: B's tensions (§6.3, §6.4)
    /// and the Gent lock-up (§6.6); outside the model, loss of tension 1.
    pub fn stretch_only_failure(&self) -> Option<FailureMode> {
        if !self.in_model {
            return Some(FailureMode::LossOfTension1);
        }
        [
            (FailureMode::LossOfTension1, self.tension_1b),
            (FailureMode::LossOfTension2b, self.tension_2b),
            (FailureMode::StretchLimit, self.lock_up),
        ]
        .into_iter()
        .find(|(_, margin)| !(*margin > T::zero()))
        .map(|(mode, _)| mode)
    }

    /// Every margin under Φ̄² (the field's square (Φ̄·λ·λ2p)² given), the breakdown's as given.
    fn with_breakdown(&self, p2: T, field_squared: T, breakdown: T) -> Margins<T> {
        let (l, l2p) = (self.stretch, self.prestretch_2);
        let tension_1a = self.stress_1a - p2 * l * l2p * l2p;
        Margins {
            values: [
                self.stiffness - p2 * l2p * l2p,
                self.hessian.under_bias(l, l2p, p2).definiteness(),
                self.tension_1b.min_margin(tension_1a),
                self.tension_2a - field_squared,
                self.tension_2b,
                breakdown,
                self.lock_up,
            ],
        }
    }
}

impl<T: Real> Device<T> {
    /// Whether the model is defined at stretch λ: both membranes have length, λ > 0 and
    /// λB > 0 (model.md §6.3). Outside it, stresses are not stresses (s1 of a negative
    /// stretch comes out positive), so no check may pass there.
    pub fn in_model(&self, stretch: T) -> bool {
        stretch > T::zero() && self.passive_stretch(stretch) > T::zero()
    }

    /// The six checks of model.md §6 at stretch λ under the dimensionless bias Φ̄²
    /// (on or off equilibrium: the dynamic monitor uses the same checks). §6.3 checks the
    /// tension in direction 1 of both B and A (A's less the electrostatic stress: the two
    /// differ along a trajectory by the bars' inertia). Outside the model (see
    /// [`Device::in_model`]) loss of tension 1 is −1 and every other margin NaN: none holds.
    pub fn margins(&self, stretch: T, bias_dimless_squared: T) -> Margins<T> {
        self.stretch_terms(stretch)
            .margins(bias_dimless_squared, self.breakdown_field_dimless())
    }

    /// The parts of the checks at stretch λ that the bias does not enter (every stress in
    /// units of μ, so the same for devices that differ only in μ: `StretchTerms`).
    pub fn stretch_terms(&self, stretch: T) -> StretchTerms<T> {
        let m = self.material();
        let l = stretch;
        let l2p = self.prestretch_2();
        let lb = self.passive_stretch(l);
        // Each piece once (the monitor's every sample), the same floats as
        // `elastic_stiffness_dimless`, `hessian`, `stress_1` and `lock_up_margin` give.
        let d11 = m.stiffness_1(l, l2p);
        let (stress_1a, lock_a) = m.stress_1_and_lock_up(l, l2p);
        let (tension_1b, lock_b) = m.stress_1_and_lock_up(lb, l2p);
        StretchTerms {
            in_model: self.in_model(l),
            stretch: l,
            prestretch_2: l2p,
            stiffness: d11 + self.length_ratio() * m.stiffness_1(lb, l2p),
            hessian: m.hessian_with(l, l2p, d11),
            tension_1b,
            stress_1a,
            tension_2a: l2p * m.stress_2(l, l2p),
            tension_2b: l2p * m.stress_2(lb, l2p),
            lock_up: lock_a.min_margin(lock_b),
        }
    }

    /// Whether `other` has this device's every parameter but μ (and the damping, which no
    /// check reads): then the two share `stretch_terms`.
    pub fn differs_only_in_modulus(&self, other: &Device<T>) -> bool {
        let (mine, theirs) = (self.params(), other.params());
        crate::model::device::DeviceParams {
            shear_modulus: mine.shear_modulus,
            damping: mine.damping,
            ..*theirs
        } == *mine
    }

    /// The first check (in model.md order) that fails at stretch λ under Φ̄²; loss of
    /// tension 1 for a state outside the model.
    pub fn first_failure(&self, stretch: T, bias_dimless_squared: T) -> Option<FailureMode> {
        self.stretch_terms(stretch)
            .first_failure(bias_dimless_squared, self.breakdown_field_dimless())
    }

    /// The checks at the equilibrium of the loading branch at stretch λ.
    pub fn margins_on_branch(&self, stretch: T) -> Margins<T> {
        self.margins_on_branch_at(stretch - self.prestretch_1())
    }

    /// The checks at the equilibrium at the offset δ = λ − λ1p on the loading branch. Each
    /// stress and invariant is its value at the pre-stretch plus a difference factored by
    /// δ, so a limit just past the pre-stretch is found to f32's relative precision in δ,
    /// not to one unit of λ's last place. On the branch A's tension in direction 1 equals
    /// B's (that is the equilibrium, model.md §5), so B's stands for both.
    pub fn margins_on_branch_at(&self, offset: T) -> Margins<T> {
        let m = self.material();
        let (l1p, l2p) = (self.prestretch_1(), self.prestretch_2());
        let l = l1p + offset;
        let passive_offset = -self.length_ratio() * offset;
        let lb = l1p + passive_offset;
        if !self.in_model(l) {
            return Margins::outside_model();
        }
        let p2 = self.bias_dimless_squared_at(offset);
        let zero = self.at_prestretch();
        let s1_b = zero.stress_1 + m.stress_1_difference(lb, l1p, passive_offset, l2p);
        let s2_a = zero.stress_2 + m.stress_2_difference(l, l1p, offset, l2p);
        let s2_b = zero.stress_2 + m.stress_2_difference(lb, l1p, passive_offset, l2p);
        let i1_0 = zero.first_invariant;
        let lock = |d: T, x: T| {
            T::one() - (i1_0 + Gent::first_invariant_difference(x, l1p, d, l2p)) * m.inv_jlim()
        };
        let field_squared = p2 * (l * l2p).squared();
        Margins {
            values: [
                self.stiffness_dimless(l, p2),
                m.hessian_under_bias(l, l2p, p2).definiteness(),
                s1_b,
                l2p * s2_a - field_squared,
                l2p * s2_b,
                self.breakdown_field_dimless() - p2.sqrt() * l * l2p,
                lock(offset, l).min_margin(lock(passive_offset, lb)),
            ],
        }
    }

    /// The stretches in which the model is defined and dynamics are guarded: from half of
    /// A's slack stretch λ2p^(−1/2) (A far in compression; λ1p if lower) up to
    /// `scan_end_stretch` (B likewise). Integrators size their step for the stiffest state here.
    pub fn model_range(&self) -> (T, T) {
        let slack_a = T::of(0.5) / self.prestretch_2().sqrt();
        (slack_a.min(self.prestretch_1()), self.scan_end_stretch())
    }

    /// The stretches a displacement sensor can plausibly report, as an open interval: the
    /// bars at most one frame length (L1·λ1p) outside the frame, λ in (−λfull, 2·λfull) with
    /// λfull = L1·λ1p/L1A (where λB = 0). Inside it, a state outside the model is loss of
    /// tension 1 (the monitor); outside it, no device could be there: a sensor fault.
    pub fn plausible_stretch(&self) -> (T, T) {
        let full = self.prestretch_1() * (T::one() + T::one() / self.length_ratio());
        (-full, full + full)
    }

    /// A stretch at which some check has surely failed on the loading branch: the least of
    /// three bounds, so the scan for the limit stays fine even on extreme geometries.
    /// - B slack: λB = ½·λ2p^(−1/2) gives s1(λB) < 0.
    /// - Stretch limit (Gent): I1 > λ² ≥ Jlim at λ = √Jlim.
    /// - Breakdown: for λ ≥ λ1p, (E/√(μ/ε))² = λ·(s̄1(λ) − s̄1(λB)) ≥ λ·(λ − k) with
    ///   k = λ1p⁻³λ2p⁻² + s̄1(λ1p) (λB ≤ λ1p, and Gent stiffens while I1 < Jlim + 3);
    ///   this passes Ē_B² at λ = (k + √(k² + 4Ē_B²))/2.
    pub fn scan_end_stretch(&self) -> T {
        let (l1p, l2p) = (self.prestretch_1(), self.prestretch_2());
        let two = T::of(2.0);
        let slack_b = T::of(0.5) / l2p.sqrt();
        let b_slack = l1p + (l1p - slack_b) / self.length_ratio();
        let inv_jlim = self.material().inv_jlim();
        let locked = if inv_jlim > T::zero() {
            (T::one() / inv_jlim).sqrt()
        } else {
            b_slack
        };
        let k = T::one() / (l1p * l1p * l1p * l2p * l2p) + self.material().stress_1(l1p, l2p);
        let eb = self.breakdown_field_dimless();
        let broken = (k + (k * k + two * two * eb * eb).sqrt()) / two * T::of(1.001);
        // Never below λ1p: a device past a bound at zero bias fails at the scan's first point.
        b_slack.min(locked).min(broken).max(l1p)
    }
}

/// The stretches the checks no bias enters allow about an equilibrium, narrowed by the
/// margin: the run-time monitor's margin on B's tensions and the Gent lock-up, which a
/// voltage raised by the margin does not move (`Device::stretch_band`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StretchBand<T> {
    pub low: T,
    pub high: T,
    /// The check that fails past each end.
    pub low_mode: FailureMode,
    pub high_mode: FailureMode,
}

impl<T: Real> StretchBand<T> {
    /// No band: every stretch inside (before the boot's direct solve finds one).
    pub fn everywhere() -> Self {
        Self {
            low: T::of(f64::NEG_INFINITY),
            high: T::of(f64::INFINITY),
            low_mode: FailureMode::LossOfTension1,
            high_mode: FailureMode::LossOfTension1,
        }
    }

    /// The check failing past the band at `stretch`, if it is outside (NaN: outside).
    pub fn outside(&self, stretch: T) -> Option<FailureMode> {
        if stretch > self.low && stretch < self.high {
            None
        } else if stretch < self.high {
            Some(self.low_mode)
        } else {
            Some(self.high_mode)
        }
    }
}

/// Halvings that find each end of a `StretchBand`.
const BAND_HALVINGS: usize = 48;

impl<T: Real> Device<T> {
    /// The stretch band about the equilibrium at `stretch` in which B's tensions and the
    /// Gent lock-up hold, each end brought toward `stretch` by `margin` of its distance;
    /// searched from `stretch` out to the model's range below and to B's zero length above.
    pub fn stretch_band(&self, stretch: T, margin: T) -> StretchBand<T> {
        let fails = |l: T| self.stretch_terms(l).stretch_only_failure();
        // From the inside (passing) to `end` (failing, or the search's end): the last
        // passing stretch and the mode past it.
        let edge = |end: T| {
            let Some(mode) = fails(end) else {
                return (end, FailureMode::LossOfTension1);
            };
            let (mut inside, mut outside, mut mode) = (stretch, end, mode);
            for _ in 0..BAND_HALVINGS {
                let mid = (inside + outside) / T::of(2.0);
                match fails(mid) {
                    Some(m) => {
                        outside = mid;
                        mode = m;
                    }
                    None => inside = mid,
                }
            }
            (inside, mode)
        };
        if fails(stretch).is_some() {
            // No band about a stretch that fails already: none passes.
            return StretchBand {
                low: stretch,
                high: stretch,
                low_mode: FailureMode::LossOfTension1,
                high_mode: FailureMode::LossOfTension1,
            };
        }
        let full = self.prestretch_1() * (T::one() + T::one() / self.length_ratio());
        let (low, low_mode) = edge(self.model_range().0.min(stretch));
        let (high, high_mode) = edge(full);
        let keep = T::one() - margin;
        StretchBand {
            low: stretch - (stretch - low) * keep,
            high: stretch + (high - stretch) * keep,
            low_mode,
            high_mode,
        }
    }
}

/// The limit of the loading branch: the first check to fail as the bias rises from zero.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limit<T> {
    pub mode: FailureMode,
    /// The last safe equilibrium: stretch, volts and natural frequency at the limit.
    pub at: Equilibrium<T>,
}

/// Grid points of the scan that brackets the limit before bisection refines it.
pub const LIMIT_SCAN_POINTS: usize = 128;

impl<T: Real> Limit<T> {
    /// The stretch on the loading branch held by `volts` (sign ignored): searched up to the
    /// limit's stretch, where Φ rises and every state is inside the model; above the limit's
    /// voltage, on to `Device::scan_end_stretch` where Φ still rises. Past a Gent lock-up Φ
    /// is not a number, so a search to the scan's end alone fails on some Gent devices.
    /// `None` if no equilibrium on the branch holds `volts` (or `volts` is NaN).
    pub fn stretch_for_bias(&self, device: &Device<T>, volts: T) -> Option<T> {
        device
            .stretch_for_bias(volts, self.at.stretch)
            .or_else(|| device.stretch_for_bias(volts, device.scan_end_stretch()))
    }

    /// Find the limit of the loading branch from λ1p, to full precision: a scan brackets the
    /// first failure, then each check failing at the bracket's end is bisected on its own.
    /// A check that fails and recovers inside one grid cell (1/128 of [λ1p, scan end]) is
    /// missed.
    pub fn of(device: &Device<T>) -> Self {
        // Scanned and bisected in the offset δ = λ − λ1p (see `margins_on_branch_at`).
        let end = device.scan_end_stretch() - device.prestretch_1();
        let at = |i: usize| end * T::of(i as f64) / T::of(LIMIT_SCAN_POINTS as f64);
        let mut safe = T::zero();
        for i in 0..=LIMIT_SCAN_POINTS {
            let d = at(i);
            let margins = device.margins_on_branch_at(d);
            if margins.first_failure().is_none() {
                safe = d;
                continue;
            }
            // The earliest crossing among the checks that fail at d (never at i = 0: a valid
            // device is safe at zero bias).
            let mut first: Option<(T, FailureMode)> = None;
            for mode in FailureMode::ALL {
                if margins.of(mode) > T::zero() {
                    continue;
                }
                let (crossing, _) = bisect(safe, d, |x| {
                    device.margins_on_branch_at(x).of(mode) > T::zero()
                });
                if first.is_none_or(|(best, _)| crossing < best) {
                    first = Some((crossing, mode));
                }
            }
            if let Some((offset, mode)) = first {
                return Self::at_offset(device, offset, mode);
            }
        }
        // Unreachable (a check has failed by the scan's end); stay on the safe side.
        Self::at_offset(device, safe, FailureMode::LossOfTension1)
    }

    fn at_offset(device: &Device<T>, offset: T, mode: FailureMode) -> Self {
        Self {
            mode,
            at: device.equilibrium_at(offset),
        }
    }
}

/// A check that failed along a trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Crossing<T> {
    pub mode: FailureMode,
    /// The step at which it was first seen.
    pub tick: u64,
    pub stretch: T,
}

/// The dynamic safety monitor: the six checks of model.md §6 at every observed state
/// λ(t), Φ(t), remembering the first crossing (model.md §6, last paragraph).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Monitor<T> {
    first: Option<Crossing<T>>,
}

impl<T: Real> Monitor<T> {
    pub const fn new() -> Self {
        Self { first: None }
    }

    /// Check one state; returns the failing check, if any, and keeps the first one seen.
    pub fn observe(
        &mut self,
        device: &Device<T>,
        tick: u64,
        stretch: T,
        bias_dimless_squared: T,
    ) -> Option<FailureMode> {
        let terms = device.stretch_terms(stretch);
        self.observe_terms(
            &terms,
            tick,
            bias_dimless_squared,
            device.breakdown_field_dimless(),
        )
    }

    /// `observe` with the stretch's terms already worked out (shared by devices that differ
    /// only in μ), for a device of this breakdown field over √(μ/ε).
    pub fn observe_terms(
        &mut self,
        terms: &StretchTerms<T>,
        tick: u64,
        bias_dimless_squared: T,
        breakdown_field_dimless: T,
    ) -> Option<FailureMode> {
        let mode = terms.first_failure(bias_dimless_squared, breakdown_field_dimless)?;
        if self.first.is_none() {
            self.first = Some(Crossing {
                mode,
                tick,
                stretch: terms.stretch,
            });
        }
        Some(mode)
    }

    /// The first crossing seen, if any.
    pub fn first_crossing(&self) -> Option<Crossing<T>> {
        self.first
    }
}
