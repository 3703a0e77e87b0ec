//! The swing of an AC drive about its bias (model.md §7, with §4's damping), and the six
//! checks of §6 over it with a margin: what a drive must pass before it is switched on.
//!
//! About the equilibrium λ* of the bias Φ0, with Φ = Φ0 + Φa·sin(Ωt), the force's Φ̄²·λ·λ2p²
//! (model.md §4) splits into a steady push, a force at Ω, one at 2Ω, and the same terms
//! times x = λ − λ* (the stiffness modulated at Ω and 2Ω). To first order the settled
//! motion is the sum of the three forced responses of an oscillator of stiffness k (§5's
//! ω̄², less the steady push's share) and damping c̄, each a term's force over
//! |k − (nΩ̄)² + i·c̄·nΩ̄|. The modulation pumps it (parametric resonance): near Ω̄ ≈ 2ω̄/n a
//! modulation of depth h grows the motion at the rate ω̄·h/4 against the damping's ω̄·ζ
//! and the detuning, the Mathieu equation's first tongue; at or past that threshold the
//! model gives the swing no bound. Below it, the forced swing is amplified by 1/(1 − ρ), ρ
//! the growth over its threshold. Switched on from rest, a forced term overshoots its
//! settled amplitude by the free ring it starts, at most by Ω/ω (the undamped beat), and
//! the steady push by itself (a step). Resonance at Ω ≈ ω (harmonic), at Ω ≈ ω/2 (the 2Ω
//! term: super-harmonic) and at Ω ≈ 2ω (parametric) are all in it; with no damping, one of
//! them at the drive's frequency has no bound.
//!
//! The checks then run over the whole box the swing spans, the box widened by
//! 1/(1 − margin) about λ* and the voltage raised to (Φ0 + Φa)/(1 − margin): the margin
//! of the cap, taken to the motion.

use core::fmt;

use crate::model::device::Device;
use crate::model::safety::FailureMode;
use crate::numerics::decimal::Decimal;
use crate::numerics::real::Real;

/// Stretches across the swing's box at which the checks run (the ends and between).
const BOX_POINTS: usize = 9;

/// Rounds in which the stiffness band the swing spans may widen before it settles.
const BAND_ROUNDS: usize = 16;

/// A band has settled when neither end moved by more than this, relative.
const BAND_SETTLED: f64 = 1e-3;

/// The ramp's ring, over its first-order estimate (`Device::ramp_ring`): the stiffness
/// changes along the ramp.
const RING_ALLOWANCE: f64 = 1.25;

/// Halvings in the search for the largest amplitude that fits.
const AMPLITUDE_HALVINGS: usize = 24;

/// The halvings' resolution, relative to the AC asked for (2⁻²⁴).
const AMPLITUDE_RESOLUTION: f64 = 1.0 / 16_777_216.0;

/// An AC drive on a bias, SI units, and the ramp to the bias before it, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AcDrive<T> {
    pub bias_volts: T,
    /// The AC's amplitude as commanded, V.
    pub ac_volts: T,
    pub ac_hz: T,
    /// The amplifier's bandwidth, Hz, a first-order response (∞, or anything not positive:
    /// none declared): the AC's first-order swing is taken at its output (`Device::forced`).
    pub amplifier_bandwidth_hz: T,
    pub ramp: Option<Ramp<T>>,
    /// A ring already there when the AC starts, besides the ramp's, in stretch: a trim's
    /// last pulse (a converged trim starts the AC right after it), or the swing of the drive
    /// before a new plan; counted undecayed, and through the ramp, if any, with the ramp's
    /// allowance (the stiffness changes along it).
    pub ring_stretch: T,
}

/// The ramp to the bias at the slew rate and the hold after it, before the AC starts: the
/// ring it leaves rides under the AC.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ramp<T> {
    pub from_volts: T,
    pub slew_volts_per_second: T,
    pub settle_seconds: T,
    /// Whether the membrane may still ring from a way down at the slew rate between the
    /// same voltages when the ramp starts (a boot after `clear`, a plan after `stop`: they
    /// wait for 0 V, not for the ring to die): that ring, undecayed, is counted too.
    pub after_descent: bool,
}

/// Which resonance of model.md §7 makes a swing large, or unbounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Resonance {
    /// The drive's own frequency at the natural frequency.
    Harmonic,
    /// Twice the drive's frequency (Φa² term) at the natural frequency.
    SuperHarmonic,
    /// The stiffness modulated near twice the natural frequency.
    Parametric,
    /// The drive's mean Φa²/2 leaves no stiffness at the bias.
    Static,
}

impl Resonance {
    /// Every resonance, in order (the fault log keeps one by its index).
    pub const ALL: [Resonance; 4] = [
        Resonance::Harmonic,
        Resonance::SuperHarmonic,
        Resonance::Parametric,
        Resonance::Static,
    ];
}

impl Resonance {
    /// What it is, for people.
    pub fn description(self) -> &'static str {
        match self {
            Resonance::Harmonic => "harmonic resonance (drive at the natural frequency)",
            Resonance::SuperHarmonic => {
                "super-harmonic resonance (drive at half the natural frequency)"
            }
            Resonance::Parametric => {
                "parametric resonance (drive near twice the natural frequency)"
            }
            Resonance::Static => "no stiffness left under the drive's mean",
        }
    }
}

/// The predicted swing of a drive that fits.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Swing<T> {
    /// λ* at the bias.
    pub stretch: T,
    /// The extremes λ reaches, the switch-on transient included (before the margin).
    pub low_stretch: T,
    pub high_stretch: T,
    /// The natural frequency at the bias, Hz, and the quality factor used (∞: no damping).
    pub natural_hz: T,
    pub quality_factor: T,
}

/// Why a drive's swing does not fit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SwingError<T> {
    /// No equilibrium of the loading branch holds the bias under the limit.
    NoEquilibrium { bias_volts: T },
    /// The model gives the swing no bound: too little damping at a resonance (or none
    /// known: the device's `damping` is 0 and nothing measured Q).
    Unbounded {
        resonance: Resonance,
        natural_hz: T,
        quality_factor: T,
        /// The largest AC amplitude whose swing fits, V (0: none).
        largest_ac_volts: T,
    },
    /// The swing, widened by the margin, crosses a check of model.md §6.
    Crosses {
        mode: FailureMode,
        /// The resonance that amplifies the swing most, where one does (more than twice).
        resonance: Option<Resonance>,
        /// The extremes of the predicted swing (before the margin).
        low_stretch: T,
        high_stretch: T,
        natural_hz: T,
        quality_factor: T,
        /// The largest AC amplitude whose swing fits, V (0: none).
        largest_ac_volts: T,
    },
}

impl<T: Real> fmt::Display for SwingError<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            SwingError::NoEquilibrium { bias_volts } => write!(
                f,
                "no equilibrium holds {} V under the limit",
                Decimal(bias_volts)
            ),
            SwingError::Unbounded {
                resonance,
                natural_hz,
                quality_factor,
                largest_ac_volts,
            } => write!(
                f,
                "the swing has no bound in the model: {} at {} Hz, Q {}; give the device's \
                 damping, or a trim to measure Q (trim_tolerance); the largest AC that fits \
                 is {} V",
                resonance.description(),
                Decimal(natural_hz),
                Decimal(quality_factor),
                Decimal(largest_ac_volts)
            ),
            SwingError::Crosses {
                mode,
                resonance,
                low_stretch,
                high_stretch,
                natural_hz,
                quality_factor,
                largest_ac_volts,
            } => {
                write!(
                    f,
                    "the swing λ {} .. {} (f {} Hz, Q {}",
                    Decimal(low_stretch),
                    Decimal(high_stretch),
                    Decimal(natural_hz),
                    Decimal(quality_factor),
                )?;
                if let Some(resonance) = resonance {
                    write!(f, ", {}", resonance.description())?;
                }
                write!(
                    f,
                    ") comes within the margin of {}; the largest AC that fits is {} V",
                    mode.description(),
                    Decimal(largest_ac_volts)
                )?;
                if !quality_factor.is_finite() {
                    write!(
                        f,
                        " (no damping known: give the device's damping, or measure Q)"
                    )?;
                }
                Ok(())
            }
        }
    }
}

/// The linearised motion about λ* (model.md §5), dimensionless.
struct About<T> {
    stretch: T,
    /// Φ̄0 at the bias.
    bias: T,
    /// ω̄² at the bias (model.md §5).
    stiffness: T,
    /// c̄ used: the device's, or ω̄/Q measured.
    damping: T,
    /// dω̄²/dλ at λ*: the motion's own swing modulates the stiffness by it.
    stiffness_slope: T,
}

/// Steps of the drop's energy integral up to the top (`Device::check_drop`), and the most
/// it marches below the rest.
const DROP_STEPS: usize = 128;
const DROP_MAX_STEPS: usize = 4096;

impl<T: Real> Device<T> {
    /// The output dropped from `from_volts` to 0 V at once (a dead DAC bus: the amplifier
    /// disabled), on a membrane swinging by `swing_stretch` (half its span) then: released
    /// with at most the energy at no field of its highest stretch, λ(from) + swing, and of
    /// the swing's speed there (ω·swing), it falls through its rest λ(0) and turns where the
    /// elastic energy at no field (model.md §4: the stress difference integrated from the
    /// rest) reaches that: undamped, exact for the model. That rebound, widened by
    /// 1/(1 − margin) about the rest, and the highest stretch are checked at 0 V (model.md
    /// §6); `Crosses` names the first check that fails (the rebound past the model's range:
    /// loss of tension 1). `Ok`: the rebound's lowest stretch (before the margin). Out of
    /// line: the boot's frame stays the smaller (the stack's budget).
    #[inline(never)]
    pub fn check_drop(
        &self,
        from_volts: T,
        swing_stretch: T,
        max_offset: T,
        margin: T,
    ) -> Result<T, SwingError<T>> {
        let top =
            self.offset_for_bias(from_volts, max_offset)
                .ok_or(SwingError::NoEquilibrium {
                    bias_volts: from_volts,
                })?;
        let swing = swing_stretch.abs();
        let high = top + swing;
        // At the rest (0 V), nothing drops.
        if !(high > T::zero()) {
            return Ok(self.prestretch_1());
        }
        // The restoring force at no field, the stress difference (Φ̄²·λ·λ2p² at the
        // equilibrium that would hold δ): positive above the rest, negative below.
        let l2p = self.prestretch_2();
        let force = |offset: T| {
            self.bias_dimless_squared_at(offset) * (self.prestretch_1() + offset) * l2p * l2p
        };
        let half = T::of(0.5);
        // The energy at the highest stretch, at rest there, by the trapezoid rule.
        let h = high / T::of(DROP_STEPS as f64);
        let mut energy = T::zero();
        let mut at = T::zero();
        for _ in 0..DROP_STEPS {
            energy = energy + (force(at) + force(at + h)) * half * h;
            at = at + h;
        }
        // And the swing's speed there, at the bias: ω̄²·swing².
        let bias = from_volts / self.volts_per_unit();
        let omega_squared = self.stiffness_dimless(self.prestretch_1() + top, bias * bias);
        energy = energy + half * omega_squared.max(T::zero()) * swing * swing;
        // Down from the rest until the elastic energy at no field has taken all of it.
        let (low_end, _) = self.model_range();
        let floor = low_end - self.prestretch_1();
        let mut turn = T::zero();
        let mut stored = T::zero();
        let mut steps = 0;
        let mut last = T::zero();
        while stored < energy && turn > floor && steps < DROP_MAX_STEPS {
            let next = turn - h;
            last = -(force(turn) + force(next)) * half * h;
            stored = stored + last;
            turn = next;
            steps += 1;
        }
        // The turn inside the last step, where its energy was just taken (linear in it).
        if stored >= energy && last > T::zero() {
            turn = turn + h * ((stored - energy) / last);
        }
        if !energy.is_finite() {
            return Err(SwingError::NoEquilibrium {
                bias_volts: from_volts,
            });
        }
        let rest = self.prestretch_1();
        let low = rest + turn / (T::one() - margin);
        let crossed = if !(stored >= energy) {
            Some(FailureMode::LossOfTension1)
        } else {
            self.first_failure(low, T::zero())
                .or_else(|| self.first_failure(rest + high, T::zero()))
        };
        match crossed {
            Some(mode) => Err(SwingError::Crosses {
                mode,
                resonance: None,
                low_stretch: low,
                high_stretch: rest + high,
                natural_hz: self.natural_frequency_hz_at(T::zero()),
                quality_factor: T::of(f64::INFINITY),
                largest_ac_volts: T::zero(),
            }),
            None => Ok(rest + turn),
        }
    }

    /// The predicted swing of `drive` about its bias with the margin's widening, checked
    /// against model.md §6: `Ok` where it fits. `max_offset` bounds the search for the
    /// bias's equilibrium (the limit's offset); `quality_factor` is a measured Q, which
    /// replaces the device's damping (`None`: the device's `damping`, 0 if not given).
    pub fn check_swing(
        &self,
        drive: AcDrive<T>,
        max_offset: T,
        quality_factor: Option<T>,
        margin: T,
    ) -> Result<Swing<T>, SwingError<T>> {
        let offset = self.offset_for_bias(drive.bias_volts, max_offset).ok_or(
            SwingError::NoEquilibrium {
                bias_volts: drive.bias_volts,
            },
        )?;
        let stretch = self.stretch_at(offset);
        let unit = self.volts_per_unit();
        let bias = drive.bias_volts.abs() / unit;
        let stiffness = self.stiffness_dimless(stretch, bias * bias);
        let omega = stiffness.sqrt();
        let damping = match quality_factor {
            Some(q) if q > T::zero() => omega / q,
            _ => self.damping_dimless(),
        };
        // dω̄²/dλ by a central difference (the bias term does not depend on λ).
        let h = stretch * T::of(1e-3);
        let stiffness_slope = (self.elastic_stiffness_dimless(stretch + h)
            - self.elastic_stiffness_dimless(stretch - h))
            / (h + h);
        let about = About {
            stretch,
            bias,
            stiffness,
            damping,
            stiffness_slope,
        };
        let natural_hz = omega * self.rad_per_s_per_unit() / T::of(core::f64::consts::TAU);
        let quality_factor = omega / damping;
        let drive_rad = T::of(core::f64::consts::TAU) * drive.ac_hz / self.rad_per_s_per_unit();
        // A ring already there rides through the ramp, if any, as the ramp's own does.
        let ring = match drive.ramp {
            Some(ramp) => {
                self.ramp_ring(&about, ramp, max_offset)?
                    + T::of(RING_ALLOWANCE) * drive.ring_stretch.abs()
            }
            None => drive.ring_stretch.abs(),
        };
        // The amplifier at the drive's frequency: gain 1/√(1 + x²), lag sin φ = x/√(1 + x²).
        let x = drive.ac_hz / drive.amplifier_bandwidth_hz;
        let x = if x >= T::zero() && x.is_finite() {
            x
        } else {
            T::zero()
        };
        // (Over 1, by 1/x: x² would overflow first.)
        let amplifier = if x > T::one() {
            let lag_sin = T::one() / (T::one() + T::one() / (x * x)).sqrt();
            Amplifier {
                gain: lag_sin / x,
                lag_sin,
            }
        } else {
            let gain = T::one() / (T::one() + x * x).sqrt();
            Amplifier {
                gain,
                lag_sin: x * gain,
            }
        };
        let fits = |ac: T| self.swing_fits(&about, ac / unit, drive_rad, ring, amplifier, margin);
        match fits(drive.ac_volts.abs()) {
            Ok((low_stretch, high_stretch)) => Ok(Swing {
                stretch,
                low_stretch,
                high_stretch,
                natural_hz,
                quality_factor,
            }),
            Err(failed) => {
                // The largest amplitude that fits, by halving [0, Φa].
                let (mut good, mut bad) = (T::zero(), drive.ac_volts.abs());
                if fits(good).is_err() {
                    bad = good;
                }
                for _ in 0..AMPLITUDE_HALVINGS {
                    let mid = (good + bad) / T::of(2.0);
                    if fits(mid).is_ok() {
                        good = mid;
                    } else {
                        bad = mid;
                    }
                }
                // Below the halving's resolution of the AC asked for: none fits.
                if !(good > drive.ac_volts.abs() * T::of(2.0 * AMPLITUDE_RESOLUTION)) {
                    good = T::zero();
                }
                Err(match failed {
                    Failed::Unbounded(resonance) => SwingError::Unbounded {
                        resonance,
                        natural_hz,
                        quality_factor,
                        largest_ac_volts: good,
                    },
                    Failed::Crosses(mode, resonance, low_stretch, high_stretch) => {
                        SwingError::Crosses {
                            mode,
                            resonance,
                            low_stretch,
                            high_stretch,
                            natural_hz,
                            quality_factor,
                            largest_ac_volts: good,
                        }
                    }
                })
            }
        }
    }

    /// The free ring a ramp at the slew rate leaves about λ* when the AC starts. The
    /// equilibrium moves at v = slew/(dΦ/dλ); a ramp's kink at either end, where v jumps,
    /// starts a ring of v/ω (a linear oscillator's; a constant-rate ramp of Tr seconds
    /// leaves at most 2v/ω, its |2·sin(ωTr/2)|·v/ω), and a ramp faster than the membrane
    /// leaves at most the step Δλ. Both ends' kinks summed, the lesser of that and the
    /// step, with `RING_ALLOWANCE` for the stiffness's change along the way; decayed over
    /// the hold at the damping's rate; and once more, undecayed, after a way down.
    fn ramp_ring(
        &self,
        about: &About<T>,
        ramp: Ramp<T>,
        max_offset: T,
    ) -> Result<T, SwingError<T>> {
        let from =
            self.offset_for_bias(ramp.from_volts, max_offset)
                .ok_or(SwingError::NoEquilibrium {
                    bias_volts: ramp.from_volts,
                })?;
        let to = about.stretch - self.prestretch_1();
        let step = (to - from).abs();
        if !(step > T::zero()) {
            return Ok(T::zero());
        }
        // v/ω at an end of the ramp, in stretch: dΦ/dλ by a difference on the side of the
        // ramp (toward the other end), ω there.
        let kink = |offset: T, toward: T| {
            let h = (toward - offset) * T::of(1e-3);
            let slope = (self.bias_volts_at(offset + h) - self.bias_volts_at(offset)) / h;
            let omega = T::of(core::f64::consts::TAU) * self.natural_frequency_hz_at(offset);
            ramp.slew_volts_per_second / (slope.abs() * omega)
        };
        let kinks = kink(from, to) + kink(to, from);
        let ring = if kinks < step { kinks } else { step };
        // The envelope's rate, 1/s: c̄/2 in the model's time.
        let rate = about.damping * self.rad_per_s_per_unit() / T::of(2.0);
        let decay = (-(rate * ramp.settle_seconds.max(T::zero()))).exp();
        let decay = if decay < T::one() { decay } else { T::one() };
        let rings = if ramp.after_descent {
            decay + T::one()
        } else {
            decay
        };
        Ok(T::of(RING_ALLOWANCE) * ring * rings)
    }

    /// The swing's extremes (before the margin) for the dimensionless amplitude `ac` at the
    /// dimensionless drive frequency `drive`, where they and the box widened by the margin
    /// pass every check; else why not. The stiffness the motion sees varies over its own
    /// swing, and with it the natural frequency: each term's response is taken at the worst
    /// stiffness in the band the swing spans (a resonance the swing can bend onto counts as
    /// hit), the band widened round by round until the swing it gives stays inside it.
    fn swing_fits(
        &self,
        about: &About<T>,
        ac: T,
        drive: T,
        ring: T,
        amplifier: Amplifier<T>,
        margin: T,
    ) -> Result<(T, T), Failed<T>> {
        let l2 = self.prestretch_2().squared();
        let half_ac2 = ac * ac / T::of(2.0);
        // The stiffness under the drive's mean Φ̄0² + Φ̄a²/2.
        let mean = about.stiffness - l2 * half_ac2;
        if !(mean > T::zero()) {
            return Err(Failed::Unbounded(Resonance::Static));
        }
        let mean_p2 = about.bias * about.bias + half_ac2;
        let widen = T::one() / (T::one() - margin);
        let peak = (about.bias + ac) * widen;
        let trough = (about.bias - ac).max(T::zero());
        // The band holds the stiffness at the bias and under the drive's mean from the start.
        let mut band = (mean, about.stiffness);
        let mut resonance = None;
        for _ in 0..BAND_ROUNDS {
            let forced = self.forced(about, ac, drive, ring, amplifier, band)?;
            resonance = forced.resonance;
            let (low, high) = (forced.low, forced.high);
            let (wide_low, wide_high) = (
                about.stretch - (about.stretch - low) * widen,
                about.stretch + (high - about.stretch) * widen,
            );
            // Every check over the widened box, under the peak voltage raised by the margin
            // and under the trough (the Hessian's bias term is indefinite); and the
            // stiffness the motion sees there.
            let mut seen = band;
            for i in 0..BOX_POINTS {
                let at = T::of(i as f64) / T::of((BOX_POINTS - 1) as f64);
                let stretch = wide_low + (wide_high - wide_low) * at;
                for p in [peak, trough] {
                    if let Some(mode) = self.first_failure(stretch, p * p) {
                        return Err(Failed::Crosses(mode, resonance, low, high));
                    }
                }
                let k = self.stiffness_dimless(stretch, mean_p2);
                seen = (seen.0.min(k), seen.1.max(k));
            }
            if !(seen.0 > T::zero()) {
                return Err(Failed::Unbounded(Resonance::Static));
            }
            let settled = |was: T, now: T| (now - was).abs() <= T::of(BAND_SETTLED) * was;
            if settled(band.0, seen.0) && settled(band.1, seen.1) {
                return Ok((low, high));
            }
            band = seen;
        }
        Err(Failed::Unbounded(resonance.unwrap_or(Resonance::Harmonic)))
    }

    /// The forced swing about λ* when the stiffness may lie anywhere in `band` (ω̄² under
    /// the drive's mean): each term at the worst stiffness of the band; the first-order
    /// term's at the amplifier's output where that bounds it more tightly.
    fn forced(
        &self,
        about: &About<T>,
        ac: T,
        drive: T,
        ring: T,
        amplifier: Amplifier<T>,
        (stiff_low, stiff_high): (T, T),
    ) -> Result<Forced<T>, Failed<T>> {
        let (zero, one, two) = (T::zero(), T::one(), T::of(2.0));
        let l2 = self.prestretch_2().squared();
        let half_ac2 = ac * ac / two;
        let force = l2 * about.stretch;
        let c = about.damping;
        // |k − w² + i·c·w| at the k of the band nearest w²: the term's smallest denominator.
        let worst = |w: T| {
            let nearest = (w * w).max(stiff_low).min(stiff_high);
            let detuned = nearest - w * w;
            let gain = (detuned * detuned + (c * w) * (c * w)).sqrt();
            (gain, nearest)
        };
        let (first_denominator, _) = worst(drive);
        let (second_denominator, _) = worst(two * drive);
        let first = force * two * about.bias * ac / first_denominator;
        // The first-order motion fed back through ℓ2·x·(Φ̄² − Φ̄0²): its product with the
        // force's Ω term, ℓ2·Φ̄0·Φ̄a·x1, adds to the steady push and to the force at 2Ω
        // (taken with the sign that adds).
        let fed_back = l2 * about.bias * ac * first;
        let steady = (force * half_ac2 + fed_back) / stiff_low;
        let second = (force * half_ac2 + fed_back) / second_denominator;
        // The modulation's depths over the stiffness at Ω and at 2Ω, pumping at the Mathieu
        // equation's first tongue ν ≈ 2ω: growth ω·h/4 against ω·ζ and the detuning, at
        // the band's ω nearest ν/2.
        let pump = |depth: T, nu: T| {
            let half = nu / two;
            let omega = half.max(stiff_low.sqrt()).min(stiff_high.sqrt());
            let zeta = c / (two * omega);
            let detuning = (half - omega) / omega;
            depth / stiff_low / T::of(4.0) / (zeta * zeta + detuning * detuning).sqrt()
        };
        // At Ω the stiffness is modulated by the drive (2·Φ̄0·Φ̄a·ℓ2) and by the motion's own
        // swing through the stiffness's slope (dω̄²/dλ·x1).
        let by_drive = two * about.bias * ac * l2;
        let at_drive = by_drive + (about.stiffness_slope * first).abs();
        let (rho_drive, rho_twice) = (pump(at_drive, drive), pump(half_ac2 * l2, two * drive));
        let rho = rho_drive.max(rho_twice);
        if ac == zero {
            return Ok(Forced {
                low: about.stretch - ring,
                high: about.stretch + ring,
                resonance: None,
            });
        }
        // A forced term unbounded (no damping on its resonance), or pumped past the
        // threshold: no bound. NaN counts as none.
        if !first.is_finite() {
            return Err(Failed::Unbounded(Resonance::Harmonic));
        }
        if !second.is_finite() {
            return Err(Failed::Unbounded(Resonance::SuperHarmonic));
        }
        // The modulation at Ω pumps near Ω ≈ 2ω (parametric resonance), by the drive's own
        // modulation; where only the motion's swing takes it past, the swing's resonance is
        // the cause (the harmonic's, here). The one at 2Ω pumps near Ω ≈ ω, the drive's own
        // resonance.
        if !(pump(by_drive, drive) < one) {
            return Err(Failed::Unbounded(Resonance::Parametric));
        }
        if !(rho_drive < one) || !(rho_twice < one) {
            return Err(Failed::Unbounded(Resonance::Harmonic));
        }
        let pumped = one / (one - rho);
        // The resonance behind the largest amplification (more than twice), for the message.
        let gains = [
            (Resonance::Harmonic, stiff_low / first_denominator),
            (Resonance::SuperHarmonic, stiff_low / second_denominator),
            (Resonance::Parametric, pumped),
        ];
        let resonance = gains
            .into_iter()
            .filter(|(_, gain)| *gain > two)
            .fold(None, |best: Option<(Resonance, T)>, (r, gain)| match best {
                Some((_, g)) if !(gain > g) => best,
                _ => Some((r, gain)),
            })
            .map(|(r, _)| r);
        // Switched on: each forced term's free ring, at most Ω/ω of it, the steady push's
        // step overshoot, and the ring the ramp left (all pumped alike).
        let omega = stiff_low.sqrt();
        let overshoot = |n: T| one + n * drive / omega;
        // The first-order term behind the amplifier, the lesser of two bounds. As commanded:
        // a first order's output is a weighted mean of the command's past (an impulse
        // response ≥ 0 of area 1), so the motion it drives, linear in it, stays within the
        // command's own. At the output: its sine, gain g, starts at phase −φ, so its free
        // ring is at most max(1, Ω/ω) of it; and the output's decaying term g·sin φ·e^(−t/τ),
        // a force falling from its start, moves the membrane at most twice its static
        // deflection (the step response's bound).
        let commanded = first * overshoot(one);
        let at_output = amplifier.gain * first * (one + (drive / omega).max(one))
            + two * amplifier.gain * amplifier.lag_sin * force * two * about.bias * ac / stiff_low;
        let first_swing = commanded.min(at_output);
        let amplitude = pumped * (first_swing + second * overshoot(two) + ring);
        let (low, high) = (
            about.stretch - amplitude,
            about.stretch + two * steady + amplitude,
        );
        if !(low.is_finite() && high.is_finite()) {
            return Err(Failed::Unbounded(resonance.unwrap_or(Resonance::Harmonic)));
        }
        Ok(Forced {
            low,
            high,
            resonance,
        })
    }
}

/// The amplifier at the drive's frequency: its gain, and the sine of its lag.
#[derive(Clone, Copy)]
struct Amplifier<T> {
    gain: T,
    lag_sin: T,
}

/// A forced swing's extremes (before the margin) and the resonance behind it.
struct Forced<T> {
    low: T,
    high: T,
    resonance: Option<Resonance>,
}

/// Why one amplitude does not fit (the search's verdict before it is said).
#[derive(Clone, Copy)]
enum Failed<T> {
    Unbounded(Resonance),
    Crosses(FailureMode, Option<Resonance>, T, T),
}
