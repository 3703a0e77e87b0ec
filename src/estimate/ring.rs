//! Closed-loop trim (beyond the paper): measure the natural frequency the plant actually
//! has, from the ring-down after a short voltage pulse, and re-estimate its shear modulus μ
//! so that the model's f at the applied bias (model.md §5) is the one measured.

use core::fmt;

use crate::numerics::decimal::Decimal;

use crate::model::device::{Device, DeviceParams};
use crate::model::safety::Limit;
use crate::numerics::roots::bisect;

/// Most samples a measurement window may hold (0.5 s at 1 kHz; 2 KB of the controller). At
/// a faster tick each sample is the mean of a stride of ticks (`Settings::trim_window`).
pub const MAX_WINDOW: usize = 512;

/// Fewest window samples per target period (the crossings' linear interpolation stays
/// within the fit's averaging at 8).
pub const MIN_SAMPLES_PER_PERIOD: f32 = 8.0;

/// Fewest crossings (both ways) a ring must show to be measured (three periods).
pub const MIN_CROSSINGS: usize = 6;

/// Fewest target periods a window must span: the crossings' three, and the one the
/// high-pass takes off its ends (`high_passed`).
pub const MIN_WINDOW_PERIODS: f32 = MIN_CROSSINGS as f32 / 2.0 + 1.0;

/// The least resolution (`RingFit::resolution`) a ring must show to be timed, in either
/// input. On the reference device (BENCHMARKS.md) the crossings locked onto the noise's wander
/// in some seeds at 39 and below (the frequency percent off); none did in twelve at 43 and
/// more. The bound is a quarter above the highest lost.
pub const MIN_RESOLUTION: f32 = 50.0;

/// The relative error of the ring's frequency, times its resolution: one standard deviation,
/// measured (BENCHMARKS.md: on the charge 0.026–0.038 in each fifth of 143 trims in the closed
/// loop against the plant's own frequency, resolutions 70 to 995, and 0.031 on a white-noise
/// ring; on the stretch 0.98 of it on white noise; 1.00 of it RMS over 1,374 readings of
/// random devices and front ends, either input). The trim asks twice that below its tolerance before it calls the frequency on target.
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
    /// The ring is too weak against its input's noise to be timed to the tolerance
    /// (`RingFit`, `RingInput::resolution`): no estimate is made from it. `ring` is its
    /// amplitude (`input.unit()`), `noise` the input's a tick (`input.noise_unit()`), heard
    /// as `from` says.
    Unresolvable {
        input: RingInput,
        from: NoiseFrom,
        resolution: f32,
        needed: f32,
        ring: f32,
        noise: f32,
    },
    /// The ring gives a shear modulus, Pa, outside the range of the batch the image was made
    /// for (model.md §10): the membrane is not what the image declares.
    OutsideBatch {
        shear_modulus: f32,
        low: f32,
        high: f32,
    },
}

/// Where a refusal's noise figure came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NoiseFrom {
    /// The image's front end (its declared noise and quantisation), before any voltage.
    Image,
    /// Heard in the hold before the pulse.
    Hold,
    /// Heard in the window after it.
    Window,
}

impl NoiseFrom {
    /// Every source, in order (the fault log keeps one by its index).
    pub const ALL: [NoiseFrom; 3] = [NoiseFrom::Image, NoiseFrom::Hold, NoiseFrom::Window];
}

impl NoiseFrom {
    const fn words(self) -> &'static str {
        match self {
            NoiseFrom::Image => "declared in the image, before any voltage",
            NoiseFrom::Hold => "heard in the hold before the pulse",
            NoiseFrom::Window => "heard in the window after it",
        }
    }
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
                input,
                from,
                resolution,
                needed,
                ring,
                noise,
            } => {
                let (what, remedy) = match input {
                    RingInput::Stretch => ("stretch", "a finer or quieter stretch sensor"),
                    RingInput::Charge => ("current", "a displacement sensor"),
                };
                write!(
                    f,
                    "the ring in the {what} is too weak to time: {}{} against {} noise of {}{} \
                     a tick ({}): resolution {}, {} needed ({}x the ring would do); fit \
                     {remedy}, raise trim_pulse_volts or trim_window_seconds, or widen \
                     trim_tolerance",
                    Decimal(ring),
                    input.unit(),
                    input.noise_source(),
                    Decimal(noise),
                    input.noise_unit(),
                    from.words(),
                    Decimal(resolution),
                    Decimal(needed),
                    Decimal(needed / resolution),
                )
            }
            TrimError::NotConverged {
                measured_hz,
                target_hz,
            } => write!(
                f,
                "trim did not converge: {} Hz measured for a target of {} Hz",
                Decimal(measured_hz),
                Decimal(target_hz)
            ),
            TrimError::OutsideBatch {
                shear_modulus,
                low,
                high,
            } => write!(
                f,
                "the membrane is not what the image declares: the ring gives shear_modulus \
                 {} Pa, outside the batch's {} .. {} Pa",
                Decimal(shear_modulus),
                Decimal(low),
                Decimal(high)
            ),
        }
    }
}

/// A ring timed by `ring_frequency_hz`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timed {
    /// Its frequency, Hz.
    pub hz: f32,
    /// The share of the window's samples the crossings counted span (1: all).
    pub span: f32,
    /// The frequency's relative standard error from the crossings' own scatter (0: none
    /// seen).
    pub scatter: f32,
}

/// The frequency of the ring in `samples` (at `sample_hz`, NaN where there was none), Hz.
/// The trend (creep, drift) is taken off by a least-squares line; the crossings of zero, both
/// ways, are found by linear interpolation; a least-squares line through crossing time
/// against crossing number for each way (upward, downward) gives a period each, and f is
/// one over their mean. A crossing counts only once the ring has left the band ±`band` on
/// the other side since the last: noise about a zero adds no crossings (0 takes every
/// crossing). Where a decaying ring fades into the noise, its crossings come too soon or
/// too late: counting stops at the first more than half a half period off the crossings'
/// own mean interval (`half_samples`, half a period as expected in samples, where too few
/// are seen to tell), as a miscounted crossing would shift every count after it. The
/// crossings' scatter about their lines, a further pass, says how well the period is known
/// whatever the noise's colour and the ring's decay.
pub fn ring_frequency_hz(
    samples: impl Iterator<Item = f32> + Clone,
    sample_hz: f32,
    band: f32,
    half_samples: f32,
) -> Result<Timed, TrimError> {
    let (finite, st, sy, stt, sty) = line_sums(samples.clone());
    let det = finite * stt - st * st;
    if !(finite >= 3.0 && det > 0.0) {
        return Err(TrimError::NoRing { crossings: 0 });
    }
    let slope = (finite * sty - st * sy) / det;
    let mut trend = Trend {
        offset: (sy - slope * st) / finite,
        slope,
        middle: samples.clone().count() as f32 * 0.5,
        band: if band > 0.0 { band } else { 0.0 },
        half_samples: 0.0,
    };
    // The half period the crossings are held to: their own mean interval, unchecked (a
    // plant far off the model's frequency is still timed), else the one expected.
    let (mut first, mut last, mut count) = (0.0f32, 0.0f32, 0.0f32);
    trend.crossings(samples.clone(), f32::INFINITY, |k, at| {
        if k == 0.0 {
            first = at;
        }
        last = at;
        count += 1.0;
    });
    trend.half_samples = if count >= MIN_CROSSINGS as f32 {
        (last - first) / (count - 1.0)
    } else {
        half_samples
    };
    // Crossing number against crossing time, summed as they come, upward and downward
    // crossings apart: each way's line takes its own offset (the trend line's error and a
    // large ring's mean moving with its amplitude shift the two ways oppositely, which a
    // line through both would take partly as slope), and the two slopes' mean cancels what of
    // that offset moves along the window.
    let mut ways = [[0.0f32; 5]; 2];
    trend.crossings(samples.clone(), f32::INFINITY, |k, at| {
        let way = (k as usize) & 1;
        if let Some([n, st, sy, stt, sty]) = ways.get_mut(way) {
            let j = libm::floorf(0.5 * k);
            *st += j;
            *sy += at;
            *stt += j * j;
            *sty += j * at;
            *n += 1.0;
        }
    });
    let slope = |[n, st, sy, stt, sty]: [f32; 5]| {
        let det = n * stt - st * st;
        (n >= 3.0 && det > 0.0).then(|| (n * sty - st * sy) / det)
    };
    let n = ways[0][0] + ways[1][0];
    let (Some(even), Some(odd), true) = (slope(ways[0]), slope(ways[1]), n >= MIN_CROSSINGS as f32)
    else {
        return Err(TrimError::NoRing {
            crossings: n.min(f32::from(u16::MAX)) as u16,
        });
    };
    // Each way's slope is a period.
    let samples_per_crossing = 0.25 * (even + odd);
    // The crossings' own scatter about each way's line, less its share along a parabola in
    // the crossing number (a chirp: a large ring's frequency moves as it decays, which is no
    // noise): the timing's error whatever the noise's colour (an ADC's is not white; noise
    // at the ring's frequency moves the crossings more than its fourth differences say).
    let lines = [(ways[0], even), (ways[1], odd)]
        .map(|([n, st, sy, ..], slope)| (slope, (sy - slope * st) / n));
    let middle = 0.5 * (n - 1.0);
    let mean_square = (n * n - 1.0) / 12.0;
    let (mut rr, mut rq, mut qq) = (0.0f32, 0.0f32, 0.0f32);
    trend.crossings(samples, n, |k, at| {
        if let Some(&(slope, first)) = lines.get((k as usize) & 1) {
            let r = at - (first + slope * libm::floorf(0.5 * k));
            let q = (k - middle) * (k - middle) - mean_square;
            rr += r * r;
            rq += r * q;
            qq += q * q;
        }
    });
    let residuals = (rr - if qq > 0.0 { rq * rq / qq } else { 0.0 }).max(0.0);
    // Each way's slope's variance: σ² over Σ(j − j̄)² = m(m² − 1)/12 for its m crossings;
    // the period is their mean.
    let sigma_squared = residuals / (n - 5.0);
    let spread = |m: f32| m * (m * m - 1.0) / 12.0;
    let period_variance =
        0.25 * sigma_squared * (1.0 / spread(ways[0][0]) + 1.0 / spread(ways[1][0]));
    let scatter = libm::sqrtf(period_variance) / (2.0 * samples_per_crossing);
    // Of the samples the high-pass left.
    let span = (n - 1.0) * samples_per_crossing / finite;
    Ok(Timed {
        hz: sample_hz / (2.0 * samples_per_crossing),
        span: span.min(1.0),
        // No scatter to tell (NaN): none claimed; an infinite one says so.
        scatter: if scatter >= 0.0 {
            scatter
        } else {
            f32::INFINITY
        },
    })
}

/// The line `ring_frequency_hz` takes off the samples, and how it counts crossings.
struct Trend {
    offset: f32,
    slope: f32,
    middle: f32,
    band: f32,
    half_samples: f32,
}

impl Trend {
    /// Each counted crossing in turn, at most `most`: (its number, its time from the middle,
    /// samples).
    fn crossings(
        &self,
        samples: impl Iterator<Item = f32>,
        most: f32,
        mut each: impl FnMut(f32, f32),
    ) {
        let mut previous: Option<(usize, f32)> = None;
        // The side of the band the ring was last beyond (true: above), and the last zero
        // crossing since: counted once the ring is beyond the band on the other side.
        let mut side: Option<bool> = None;
        let mut last_zero: Option<f32> = None;
        let mut last_at = f32::NAN;
        let mut n = 0.0f32;
        for (k, y) in samples.enumerate() {
            if !y.is_finite() {
                continue;
            }
            let r = y - (self.offset + self.slope * (k as f32 - self.middle));
            if let Some((j, p)) = previous {
                if (p < 0.0) != (r < 0.0) {
                    last_zero = Some(j as f32 + (k - j) as f32 * (-p / (r - p)) - self.middle);
                }
            }
            previous = Some((k, r));
            let now = if r > self.band {
                true
            } else if r < -self.band {
                false
            } else {
                continue;
            };
            if let (Some(was), Some(at)) = (side, last_zero) {
                if was != now {
                    let interval = at - last_at;
                    let half = self.half_samples;
                    let regular = interval >= 0.5 * half && interval <= 1.5 * half;
                    if n >= most || (half > 0.0 && n > 0.0 && !regular) {
                        return;
                    }
                    each(n, at);
                    last_at = at;
                    n += 1.0;
                }
            }
            side = Some(now);
            last_zero = None;
        }
    }
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

/// The input a ring is timed in: the stretch from a displacement sensor (white noise a
/// sample), or the charge, the running sum of the amplifier's current (a random walk).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RingInput {
    Stretch,
    Charge,
}

impl RingInput {
    /// Both inputs, in order (the fault log keeps one by its index).
    pub const ALL: [RingInput; 2] = [RingInput::Stretch, RingInput::Charge];
}

impl RingInput {
    /// The ring's unit, for a refusal's words (with its space; the stretch has none).
    pub const fn unit(self) -> &'static str {
        match self {
            RingInput::Stretch => "",
            RingInput::Charge => " C",
        }
    }

    /// The noise's unit a tick (the stretch sensor's, or the current monitor's; as `unit`).
    pub const fn noise_unit(self) -> &'static str {
        match self {
            RingInput::Stretch => "",
            RingInput::Charge => " A",
        }
    }

    /// What the noise is the noise of.
    pub const fn noise_source(self) -> &'static str {
        match self {
            RingInput::Stretch => "the stretch sensor's",
            RingInput::Charge => "the current monitor's",
        }
    }

    /// The ring in the window's unit (A·ticks, stretch·ticks: both inputs are timed in their
    /// running sum) for a ring of `ring` (C, stretch) at `hz`, ticking at `tick_hz`: the
    /// charge is the current's sum already; the stretch's sum carries a ring of a·P/(2π),
    /// P = tick_hz/hz ticks a period.
    pub fn in_window(self, ring: f32, hz: f32, tick_hz: f32) -> f32 {
        match self {
            RingInput::Charge => ring * tick_hz,
            RingInput::Stretch => ring * tick_hz / (core::f32::consts::TAU * hz),
        }
    }
}

/// The variance of a random walk of unit steps less its centred mean over L = 2h + 1 steps
/// (`high_passed`, h = `half`): h(h + 1)/(3L).
fn walk_variance(half: usize) -> f32 {
    let h = half as f32;
    h * (h + 1.0) / (3.0 * (2.0 * h + 1.0))
}

/// What a window of a ring input's running sum (a sample the mean of a stride of ticks)
/// tells of its own ring and noise, from the window alone. Both inputs are timed so: the
/// current's sum is the charge (Q = C(λ)·Φ, model.md §8); the stretch's sum turns a
/// sensor's white noise into the same slow wander, which the high-pass (`high_passed`)
/// follows and the crossings' fit averages out, where white noise on the stretch itself adds
/// crossings near each zero. One rule then holds for every ring (`resolution`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RingFit {
    /// The ring's amplitude in the sum (A·ticks, stretch·ticks): from the high-passed
    /// window's mean square less the noise's share of it.
    pub amplitude: f32,
    /// The noise of the sum's steps from sample to sample (the input's noise summed over a
    /// stride), never below the floor given (the noise the front end declares,
    /// `acquire::InputNoise`). From the fourth differences of the sum (the input's third,
    /// variance 20·σ² for white noise), which a ring of eight or more samples a period passes
    /// at most (2·sin(π/8))⁴ = 0.34 of, far less at the usual 20 and more.
    pub noise: f32,
    /// The ring against the noise it is timed through: its amplitude over the high-passed
    /// noise of a period, √P·noise, times the periods in the window N/P. The frequency's
    /// relative error goes as its inverse (`TIMING_ERROR_TIMES_RESOLUTION`).
    pub resolution: f32,
}

impl RingFit {
    /// The ring and noise of `samples`, high-passed over `2·half + 1` of them (a period), the
    /// noise taken as at least `floor` a sample.
    pub fn of(samples: &[f32], half: usize, floor: f32) -> Self {
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
        let heard = sum / (20.0 * count);
        // A floor that is no number says nothing; an infinite one leaves no resolution.
        let floor = if floor >= 0.0 { floor } else { 0.0 };
        let noise_squared = if heard >= floor * floor {
            heard
        } else {
            floor * floor
        };
        let (mut square, mut n) = (0.0f32, 0.0f32);
        for y in high_passed(samples, half) {
            if y.is_finite() {
                square += y * y;
                n += 1.0;
            }
        }
        let span = 2.0 * half as f32 + 1.0;
        let walk = noise_squared * walk_variance(half);
        let amplitude = libm::sqrtf(2.0 * (square / n - walk).max(0.0));
        let noise = libm::sqrtf(noise_squared);
        let resolution = Self::resolution(amplitude, noise, span, n / span);
        Self {
            amplitude,
            noise,
            resolution: if resolution.is_nan() { 0.0 } else { resolution },
        }
    }

    /// The band about zero (`ring_frequency_hz`) that the high-passed noise leaves only one
    /// time in 370, for this window's noise (`band_of`).
    pub fn band(&self, half: usize) -> f32 {
        Self::band_of(self.noise, half)
    }

    /// The band for steps of `noise` high-passed over `2·half + 1` samples: three deviations
    /// of the walk left (`walk_variance`).
    pub fn band_of(noise: f32, half: usize) -> f32 {
        3.0 * noise * libm::sqrtf(walk_variance(half))
    }

    /// The resolution of a ring of `amplitude` through steps of `noise` (the same unit, a
    /// sample), `per_period` samples a period over `periods` periods: the one rule every ring
    /// the trim times is held to, from its window or predicted before its pulse.
    pub fn resolution(amplitude: f32, noise: f32, per_period: f32, periods: f32) -> f32 {
        amplitude / (noise * libm::sqrtf(per_period)) * periods
    }

    /// The resolution a measurement needs: `MIN_RESOLUTION`, and one that finds the
    /// frequency within `tolerance` (relative), its timing error's two deviations within two
    /// thirds of the tolerance, so that a third is left for the trim to land in. Every
    /// reading is held to it, the first too: a reading's error moves the next bias by it
    /// over the device's tuning slope, which on a barely tunable device is the whole range.
    pub fn needed(tolerance: f32) -> f32 {
        let by_tolerance = 3.0 * TIMING_ERROR_TIMES_RESOLUTION / tolerance;
        if by_tolerance > MIN_RESOLUTION {
            by_tolerance
        } else {
            MIN_RESOLUTION
        }
    }
}

/// A ring's quality factor from its decay over a window (model.md §7: a free ring's
/// amplitude falls as e^(−ω·t/(2Q)), Q = ω·M/c), with the highest Q the window allows.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RingQuality {
    /// Q from the amplitudes of the window's two halves (∞: no decay heard).
    pub quality_factor: f32,
    /// The highest Q within the halves' errors, `QUALITY_DEVIATIONS` deviations of their
    /// ratio (∞: the decay is not told from none).
    pub high: f32,
}

/// The deviations of the halves' amplitude ratio `RingQuality::high` allows.
pub const QUALITY_DEVIATIONS: f32 = 3.0;

/// The least relative error a half's amplitude is taken to have, however quiet the ring: an
/// allowance for a decay not quite one exponential (a viscous branch's) and for the fit.
pub const MIN_AMPLITUDE_ERROR: f32 = 2e-3;

impl RingQuality {
    /// The decay of the ring in `samples` (a ring input's running sum, as `RingFit` takes
    /// it, `samples_per_second` of them) at `ring_hz`, high-passed over `2·half + 1` samples
    /// (a period), the noise at least `floor` a sample (`RingFit`'s): the amplitudes of its
    /// two halves (`amplitude`; a ring decaying at δ has the second's e^(−δ·Δ) times the
    /// first's, Δ the halves' distance, each fitted over an equal span) and their errors
    /// (`relative_error`).
    pub fn of(
        samples: &[f32],
        half: usize,
        floor: f32,
        samples_per_second: f32,
        ring_hz: f32,
    ) -> Self {
        const UNBOUNDED: RingQuality = RingQuality {
            quality_factor: f32::INFINITY,
            high: f32::INFINITY,
        };
        // No frequency, no time: nothing bounds Q.
        if !(ring_hz > 0.0 && samples_per_second > 0.0) {
            return UNBOUNDED;
        }
        let n = samples.len() / 2;
        let turn = core::f32::consts::TAU * ring_hz / samples_per_second;
        let halves = [samples.get(..n), samples.get(n..2 * n)].map(|h| h.unwrap_or(&[]));
        let [first, second] =
            halves.map(|h| (RingFit::of(h, half, floor), Self::amplitude(h, half, turn)));
        let per_period = 2.0 * half as f32 + 1.0;
        let error = |(fit, (amplitude, valid)): (RingFit, (f32, f32))| {
            Self::relative_error(fit.noise, amplitude, valid, per_period).max(MIN_AMPLITUDE_ERROR)
        };
        let (a, b) = (error(first), error(second));
        let spread = libm::sqrtf(a * a + b * b);
        let ratio = libm::logf(first.1 .0 / second.1 .0);
        // δ = ln(A₁/A₂)/Δ, Q = ω/(2δ) = π·f/δ.
        let seconds = n as f32 / samples_per_second;
        let quality = |log_ratio: f32| {
            if log_ratio > 0.0 {
                core::f32::consts::PI * ring_hz * seconds / log_ratio
            } else {
                f32::INFINITY
            }
        };
        // (A ratio or spread that is no number gives ∞: `quality`'s test fails on NaN.)
        RingQuality {
            quality_factor: quality(ratio),
            high: quality(ratio - QUALITY_DEVIATIONS * spread),
        }
    }

    /// The amplitude of the sine of `turn` radians a sample that fits `samples` high-passed
    /// over `2·half + 1` of them best (least squares in its sine and cosine): exact for a
    /// steady ring whatever its phase, where a mean square over a part of a period is not;
    /// and how many high-passed samples it was fitted over (a missing sample takes a
    /// period's with it).
    fn amplitude(samples: &[f32], half: usize, turn: f32) -> (f32, f32) {
        let mut valid = 0.0f32;
        let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (k, y) in high_passed(samples, half).enumerate() {
            if y.is_finite() {
                valid += 1.0;
                let (sin, cos) = (libm::sinf(turn * k as f32), libm::cosf(turn * k as f32));
                ss += sin * sin;
                sc += sin * cos;
                cc += cos * cos;
                ys += y * sin;
                yc += y * cos;
            }
        }
        let det = ss * cc - sc * sc;
        let (a, b) = ((ys * cc - yc * sc) / det, (yc * ss - ys * sc) / det);
        (libm::sqrtf(a * a + b * b), valid)
    }

    /// A half's `amplitude`'s relative error (one deviation), fitted over `valid` high-passed
    /// samples, `per_period` a period. Their noise w is the walk of steps of `noise`
    /// (variance `walk_variance`), correlated over about a period (L samples): the fit's
    /// cross term with the ring, 2·A·w·sin, averages to a deviation of A·σ_w·√(2L/n), the
    /// noise's own square to σ_w²·√(2L/n); over A²/2, an amplitude's relative error is half
    /// its square's. NaN or ∞ where no ring was heard.
    fn relative_error(noise: f32, amplitude: f32, valid: f32, per_period: f32) -> f32 {
        let half = ((per_period - 1.0) * 0.5) as usize;
        let noise = noise * libm::sqrtf(walk_variance(half)) / amplitude;
        libm::sqrtf(2.0 * per_period / valid) * (noise + noise * noise)
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

/// The ring the trim's pulse leaves, as the statics predict it (undamped: the plant's
/// damping only lowers it). The pulse, ΔΦ down for `pulse_seconds` at the bias Φ, moves the
/// equilibrium by Δλ = Φ·C'(λ)·ΔΦ/(L1A·M·ω²) (model.md §4: the electrical term of M·λ'' is
/// Φ²·C'(λ)/(2·L1A); §5: the stiffness is M·ω²) and leaves a ring of 2·Δλ·|sin(ω·T/2)| in
/// the stretch, which the charge Q = C(λ)·Φ carries as Φ·C'(λ) times it (model.md §8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RingGain {
    /// The ring in the stretch per volt of bias and per volt of pulse, 1/V².
    pub stretch_per_volt_squared: f32,
    /// C'(λ) at the bias, F: the charge's ring per volt of bias and per unit of stretch.
    pub farads_per_stretch: f32,
}

impl RingGain {
    /// Not known (no equilibrium, or no prediction wanted).
    pub const UNKNOWN: RingGain = RingGain {
        stretch_per_volt_squared: f32::NAN,
        farads_per_stretch: f32::NAN,
    };

    /// The prediction at `volts` on the loading branch below `limit_offset` (`UNKNOWN` where
    /// `volts` has no equilibrium there).
    pub fn at(device: &Device<f32>, limit_offset: f32, volts: f32, pulse_seconds: f32) -> Self {
        let Some(offset) = device.offset_for_bias(volts, limit_offset) else {
            return Self::UNKNOWN;
        };
        let p = device.params();
        let slope = 2.0 * p.farads_per_stretch_squared() * device.stretch_at(offset);
        let omega = core::f32::consts::TAU * device.natural_frequency_hz_at(offset);
        let sine = libm::fabsf(libm::sinf(0.5 * omega * pulse_seconds));
        Self {
            stretch_per_volt_squared: 2.0 * slope * sine
                / (p.length_active * p.effective_mass() * omega * omega),
            farads_per_stretch: slope,
        }
    }

    /// The ring in `input` a pulse of `pulse_volts` at `bias_volts` leaves: stretch, or C.
    pub fn ring(&self, input: RingInput, bias_volts: f32, pulse_volts: f32) -> f32 {
        let stretch = self.stretch_per_volt_squared * bias_volts * pulse_volts;
        match input {
            RingInput::Stretch => stretch,
            RingInput::Charge => self.farads_per_stretch * bias_volts * stretch,
        }
    }

    /// A ring of `ring` in `input` at `bias_volts` as the stretch's (the charge's over
    /// Φ·C'(λ), model.md §8).
    pub fn stretch_of(&self, input: RingInput, bias_volts: f32, ring: f32) -> f32 {
        match input {
            RingInput::Stretch => ring,
            RingInput::Charge => ring / (self.farads_per_stretch * bias_volts),
        }
    }
}

/// The share of a window of `window_seconds` a ring decaying at `decay_per_second` stands
/// above a band `ratio` times below its first amplitude in: its crossings count until
/// ln(ratio)/decay (`ring_frequency_hz`). 1 undamped, or where nothing says (no band).
pub fn ring_span(decay_per_second: f32, window_seconds: f32, ratio: f32) -> f32 {
    if !(decay_per_second > 0.0 && ratio.is_finite() && window_seconds > 0.0) {
        return 1.0;
    }
    let fades = libm::logf(ratio.max(1.0)) / decay_per_second;
    (fades / window_seconds).clamp(0.0, 1.0)
}

/// The share of an undamped ring's amplitude a window of `window_seconds` shows (its RMS
/// against a steady ring's) when the ring decays at `decay_per_second` (ζ·ω, 1/s; model.md
/// §7: c/(2·M)): √(τ/(2T)·(1 − e^(−2T/τ))), τ = 1/decay. 1 undamped.
pub fn ring_share(decay_per_second: f32, window_seconds: f32) -> f32 {
    let x = 2.0 * decay_per_second * window_seconds;
    if !(x > 1e-6) {
        return 1.0;
    }
    libm::sqrtf((1.0 - libm::expf(-x)) / x)
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
