//! Closed-loop trim (beyond the paper): measure the natural frequency the plant actually
//! has, from the ring-down after a short voltage pulse, and re-estimate its shear modulus μ
//! so that the model's f at the applied bias (model.md §5) is the one measured.

use core::fmt;

use crate::numerics::decimal::Decimal;

use crate::device::{Device, DeviceParams};
use crate::numerics::roots::bisect;
use crate::safety::Limit;

/// Most samples a measurement window may hold (0.5 s at 1 kHz; 2 KB of the controller). At
/// a faster tick each sample is the mean of a stride of ticks (`Settings::trim_window`).
pub const MAX_WINDOW: usize = 512;

/// Fewest window samples per target period (the crossings' linear interpolation stays
/// within the fit's averaging at 8).
pub const MIN_SAMPLES_PER_PERIOD: f32 = 8.0;

/// Fewest crossings (both ways) a ring must show to be measured (three periods).
pub const MIN_CROSSINGS: usize = 6;

/// Fewest target periods a window must span: the crossings' three, and the one the charge's
/// high-pass takes off its ends (`high_passed`).
pub const MIN_WINDOW_PERIODS: f32 = MIN_CROSSINGS as f32 / 2.0 + 1.0;

/// The least resolution (`ChargeRing::resolution`) a ring in the charge must show to be
/// timed. On the reference device (BENCHMARKS.md) the crossings locked onto the noise's wander
/// in some seeds at 39 and below (the frequency percent off); none did in twelve at 43 and
/// more. The bound is a quarter above the highest lost.
pub const MIN_RESOLUTION: f32 = 50.0;

/// The relative error of the ring's frequency from the charge, times its resolution: one
/// standard deviation, measured (BENCHMARKS.md: 0.026–0.038 in each fifth of 143 trims in the
/// closed loop against the plant's own frequency, resolutions 70 to 995; 0.031 on a white-noise
/// ring). The trim asks twice that below its tolerance before it calls the frequency on target.
pub const TIMING_ERROR_TIMES_RESOLUTION: f32 = 0.031;

/// The estimate of μ is searched within this factor of the nominal, both ways.
pub const MODULUS_RANGE: f32 = 4.0;

/// Why a trim step failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrimError {
    /// The window held too few crossings of its trend line: no ring (sensor missing or
    /// stuck, or the plant did not respond to the pulse).
    NoRing { crossings: u16 },
    /// No μ within `MODULUS_RANGE` of the nominal gives the measured frequency at the bias.
    NoEstimate { measured_hz: f32, volts: f32 },
    /// After the most trims allowed, the frequency is still off the target.
    NotConverged { measured_hz: f32, target_hz: f32 },
    /// The ring in the charge is too weak against the current monitor's noise to be timed
    /// to the tolerance (`ChargeRing`): no estimate is made from it.
    Unresolvable {
        resolution: f32,
        needed: f32,
        ring_coulombs: f32,
        noise_amps: f32,
    },
}

impl core::error::Error for TrimError {}

impl fmt::Display for TrimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            TrimError::NoRing { crossings } => write!(
                f,
                "no ring to measure after the pulse ({crossings} crossings): sensor or plant not \
                 responding"
            ),
            TrimError::NoEstimate { measured_hz, volts } => write!(
                f,
                "no shear modulus within {}x of the nominal gives {} Hz at {} V",
                Decimal(MODULUS_RANGE),
                Decimal(measured_hz),
                Decimal(volts)
            ),
            TrimError::Unresolvable {
                resolution,
                needed,
                ring_coulombs,
                noise_amps,
            } => write!(
                f,
                "the ring in the current is too weak to time: {} C of charge against the \
                 monitor's noise of {} A a tick gives a resolution of {} over the window, {} \
                 needed; fit a displacement sensor, raise trim_pulse_volts or \
                 trim_window_seconds, or widen trim_tolerance",
                Decimal(ring_coulombs),
                Decimal(noise_amps),
                Decimal(resolution),
                Decimal(needed)
            ),
            TrimError::NotConverged {
                measured_hz,
                target_hz,
            } => write!(
                f,
                "trim did not converge: {} Hz measured for a target of {} Hz",
                Decimal(measured_hz),
                Decimal(target_hz)
            ),
        }
    }
}

/// The frequency of the ring in `samples` (at `sample_hz`, NaN where there was none), Hz.
/// The trend (creep, drift) is taken off by a least-squares line; the crossings of zero, both
/// ways, are found by linear interpolation; f = 1/(2·slope) of the least-squares line
/// through crossing time against crossing number. The line's error (a ring is never quite
/// orthogonal to it: 1e-3 of f over 14 periods, measured) shifts upward and downward
/// crossings in opposite directions, and the slope fit averages that out.
pub fn ring_frequency_hz(
    samples: impl Iterator<Item = f32> + Clone,
    sample_hz: f32,
) -> Result<f32, TrimError> {
    let (mut n, mut st, mut sy, mut stt, mut sty) = line_sums(samples.clone());
    let det = n * stt - st * st;
    if !(n >= 3.0 && det > 0.0) {
        return Err(TrimError::NoRing { crossings: 0 });
    }
    let slope = (n * sty - st * sy) / det;
    let offset = (sy - slope * st) / n;
    let middle = samples.clone().count() as f32 * 0.5;
    // Crossing number against crossing time, summed as they come.
    (n, st, sy, stt, sty) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut previous: Option<(usize, f32)> = None;
    for (k, y) in samples.enumerate() {
        if !y.is_finite() {
            continue;
        }
        let r = y - (offset + slope * (k as f32 - middle));
        if let Some((j, p)) = previous {
            if (p < 0.0) != (r < 0.0) {
                let at = j as f32 + (k - j) as f32 * (-p / (r - p)) - middle;
                st += n;
                sy += at;
                stt += n * n;
                sty += n * at;
                n += 1.0;
            }
        }
        previous = Some((k, r));
    }
    let det = n * stt - st * st;
    if !(n >= MIN_CROSSINGS as f32 && det > 0.0) {
        return Err(TrimError::NoRing {
            crossings: n.min(f32::from(u16::MAX)) as u16,
        });
    }
    let samples_per_crossing = (n * sty - st * sy) / det;
    Ok(sample_hz / (2.0 * samples_per_crossing))
}

/// Each sample less the mean of the `2·half + 1` centred on it (about one period of the
/// ring; NaN where that span is not all in the window). The charge's ring rides on the
/// running sum of the monitor's noise, a random walk whose slow wander no trend line takes
/// off and which moves the crossings; the mean over a period follows the wander and leaves
/// the ring. A centred mean delays nothing, so the crossings stay where they are.
pub fn high_passed(samples: &[f32], half: usize) -> impl Iterator<Item = f32> + Clone + '_ {
    let span = (2 * half + 1) as f32;
    (0..samples.len()).map(move |k| {
        let around = k
            .checked_sub(half)
            .and_then(|from| samples.get(from..=k.saturating_add(half)));
        match (around, samples.get(k)) {
            // Differences to the sample itself: the charge's offset cancels before the sum.
            (Some(around), Some(&y)) => -around.iter().map(|&x| x - y).sum::<f32>() / span,
            _ => f32::NAN,
        }
    })
}

/// What a window of the charge (the current's running sum, in A·ticks, a sample the mean of
/// a stride of ticks) tells of its own ring and noise, from the window alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChargeRing {
    /// The ring's amplitude, A·ticks: from the high-passed window's mean square less the
    /// noise's share of it.
    pub amplitude: f32,
    /// The noise of the charge's steps from sample to sample, A·ticks: the current monitor's
    /// noise summed over a stride. From the fourth differences of the charge (the third of
    /// the current, variance 20·σ² for white noise), which a ring of eight or more samples a
    /// period passes at most (2·sin(π/8))⁴ = 0.34 of, far less at the usual 20 and more.
    pub noise: f32,
    /// The ring against the noise it is timed through: its amplitude over the high-passed
    /// noise of a period, √P·noise, times the periods in the window N/P. The frequency's
    /// relative error goes as its inverse (`TIMING_ERROR_TIMES_RESOLUTION`).
    pub resolution: f32,
}

impl ChargeRing {
    /// The ring and noise of `samples`, high-passed over `2·half + 1` of them (a period).
    pub fn of(samples: &[f32], half: usize) -> Self {
        let (mut sum, mut count) = (0.0f32, 0.0f32);
        for d in samples.windows(5) {
            if let [a, b, c, d, e] = *d {
                let fourth = a - 4.0 * b + 6.0 * c - 4.0 * d + e;
                if fourth.is_finite() {
                    sum += fourth * fourth;
                    count += 1.0;
                }
            }
        }
        let noise_squared = sum / (20.0 * count);
        let (mut square, mut n) = (0.0f32, 0.0f32);
        for y in high_passed(samples, half) {
            if y.is_finite() {
                square += y * y;
                n += 1.0;
            }
        }
        // A random walk less its centred mean over L = 2h + 1 steps: variance
        // σ²·h(h + 1)/(3L).
        let h = half as f32;
        let span = 2.0 * h + 1.0;
        let walk = noise_squared * h * (h + 1.0) / (3.0 * span);
        let amplitude = libm::sqrtf(2.0 * (square / n - walk).max(0.0));
        let noise = libm::sqrtf(noise_squared);
        let resolution = Self::resolution_of(amplitude, noise, span, n / span);
        Self {
            amplitude,
            noise,
            resolution: if resolution.is_nan() { 0.0 } else { resolution },
        }
    }

    /// The resolution of a ring of `amplitude` through steps of `noise` (the same unit, a
    /// sample), `per_period` samples a period over `periods` periods (see `resolution`).
    pub fn resolution_of(amplitude: f32, noise: f32, per_period: f32, periods: f32) -> f32 {
        amplitude / (noise * libm::sqrtf(per_period)) * periods
    }

    /// The resolution a measurement needs: `MIN_RESOLUTION`; and one that may find the
    /// frequency on target within `tolerance` (relative; the bias the tuned one), its timing
    /// error's two deviations within two thirds of the tolerance, so that a third is left
    /// for the trim to land in.
    pub fn needed(tolerance: Option<f32>) -> f32 {
        tolerance.map_or(MIN_RESOLUTION, |tolerance| {
            MIN_RESOLUTION.max(3.0 * TIMING_ERROR_TIMES_RESOLUTION / tolerance)
        })
    }
}

/// Sums for a least-squares line through (k − middle, y_k) over the finite samples:
/// (n, Σt, Σy, Σt², Σty), about the window's middle (well conditioned in f32).
fn line_sums(samples: impl Iterator<Item = f32> + Clone) -> (f32, f32, f32, f32, f32) {
    let middle = samples.clone().count() as f32 * 0.5;
    let mut sums = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for (k, y) in samples.enumerate() {
        if y.is_finite() {
            let t = k as f32 - middle;
            sums.0 += 1.0;
            sums.1 += t;
            sums.2 += y;
            sums.3 += t * t;
            sums.4 += t * y;
        }
    }
    sums
}

/// The ring the trim's pulse leaves in the charge, per volt of pulse and per volt² of bias,
/// C/V³ (NaN where `volts` has no equilibrium below `limit_offset`). The pulse, ΔΦ down for
/// `pulse_seconds`, moves the equilibrium by Δλ = Φ·C'(λ)·ΔΦ/(L1A·M·ω²) (model.md §4: the
/// electrical term of M·λ'' is Φ²·C'(λ)/(2·L1A); §5: the stiffness is M·ω²) and leaves a ring
/// of 2·Δλ·|sin(ω·T/2)| in the stretch, which the charge Q = C(λ)·Φ carries as Φ·C'(λ) times
/// it (model.md §8). Undamped: the plant's damping only lowers it.
pub fn ring_charge_gain(
    device: &Device<f32>,
    limit_offset: f32,
    volts: f32,
    pulse_seconds: f32,
) -> f32 {
    let Some(offset) = device.offset_for_bias(volts, limit_offset) else {
        return f32::NAN;
    };
    let p = device.params();
    let slope = 2.0 * p.farads_per_stretch_squared() * device.stretch_at(offset);
    let omega = core::f32::consts::TAU * device.natural_frequency_hz_at(offset);
    let sine = libm::fabsf(libm::sinf(0.5 * omega * pulse_seconds));
    2.0 * slope * slope * sine / (p.length_active * p.effective_mass() * omega * omega)
}

/// The natural frequency the model gives at `volts` on the loading branch before its limit,
/// Hz (NaN if `volts` is past the limit: beyond it a soft device finds far equilibria,
/// stiffened by lock-up, that would fool the search).
pub(crate) fn model_hz(params: &DeviceParams<f32>, volts: f32) -> f32 {
    let Ok(d) = Device::new(*params) else {
        return f32::NAN;
    };
    let limit = Limit::of(&d);
    if !(volts <= limit.at.volts) {
        return f32::NAN;
    }
    d.offset_for_bias(volts, limit.at.offset)
        .map_or(f32::NAN, |offset| d.natural_frequency_hz_at(offset))
}

/// The shear modulus μ for which the model with `params` (otherwise as they are) has the
/// natural frequency `measured_hz` at `volts`: bisection within `MODULUS_RANGE` of the
/// given μ. At a fixed bias f rises with μ (the bias's effect falls as 1/μ), so one root;
/// a μ too soft to hold the bias below its limit counts as too low.
pub fn estimate_shear_modulus(
    params: &DeviceParams<f32>,
    volts: f32,
    measured_hz: f32,
) -> Result<f32, TrimError> {
    let with = |mu: f32| DeviceParams {
        shear_modulus: mu,
        ..*params
    };
    let (low, high) = (
        params.shear_modulus / MODULUS_RANGE,
        params.shear_modulus * MODULUS_RANGE,
    );
    // Too soft to hold the bias counts as "below": the frequency there is NaN or low.
    let below_or_none = |mu: f32| {
        let f = model_hz(&with(mu), volts);
        !(f >= measured_hz)
    };
    let bracketed = below_or_none(low) && !below_or_none(high);
    if !(measured_hz.is_finite() && measured_hz > 0.0 && bracketed) {
        return Err(TrimError::NoEstimate { measured_hz, volts });
    }
    let (_, mu) = bisect(low, high, below_or_none);
    Ok(mu)
}
