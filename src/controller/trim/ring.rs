//! What the trim expects of its next ring ([`NextRing`]) and the noise it is timed against
//! ([`HoldNoise`]): whether a pulse's ring can be timed to the tolerance (`predicted`), the
//! pulse itself, and the batch's check of a re-estimated μ.

use crate::acquire::InputNoise;
use crate::controller::settings::Settings;
use crate::estimate::ring::{
    ring_share, ring_span, NoiseFrom, RingFit, RingGain, RingInput, TrimError,
};
use crate::model::device::Device;

/// The relative frequency error at which the trim before a tracked drive hands over to the
/// tracker.
pub const TRACK_HANDOVER: f32 = 0.05;

/// What the trim expects of the ring its next pulse leaves: the statics' prediction, the
/// share of its amplitude the window shows (the damping's: the device's before any window,
/// then the last window's), and the share of the window it stands out of the noise in (the
/// crossings counted: a damped ring fades into the noise; likewise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NextRing {
    pub gain: RingGain,
    pub seen: f32,
    pub span: f32,
}

impl NextRing {
    /// Nothing known: no prediction.
    pub const UNKNOWN: NextRing = NextRing {
        gain: RingGain::UNKNOWN,
        seen: 1.0,
        span: 1.0,
    };

    /// Before any window: the ring at `bias_volts` on `device` (below `limit_offset`), its
    /// share over the window at the device's damping (model.md §7: decay c/(2·M)), and the
    /// share of the window it stands above `band` in (the window's unit; 0: all).
    pub(super) fn planned(
        device: &Device<f32>,
        limit_offset: f32,
        (bias_volts, s): (f32, &Settings),
        (input, band): (RingInput, f32),
    ) -> Self {
        let gain = RingGain::at(device, limit_offset, bias_volts, pulse_seconds(s));
        let p = device.params();
        let decay = p.damping / (2.0 * p.effective_mass());
        let window = s.trim_window_seconds;
        let ring = gain.ring(input, bias_volts, s.trim_pulse_volts);
        let amplitude = input.in_window(ring, s.target_hz, s.tick_hz);
        Self {
            gain,
            seen: ring_share(decay, window),
            span: ring_span(decay, window, amplitude / band),
        }
    }
}

/// The ring input's noise in the holds before the pulses (the stretch sensor's, or the
/// current monitor's with no probe then, the bias still; heard afresh in each, but under a
/// probe only until it has been heard once: the probe is taken off for that hold, and stays
/// on in the later ones): the sums of the input's fourth differences, whose variance is
/// 70·σ² for white noise and which pass a ring of eight or more ticks a period at most
/// (2·sin(π/8))⁴ = 0.34 of its amplitude, far less at the usual twenty and more (the AC's
/// ring after a drive stops), and a trend (creep, the ramp's end) not at all.
#[derive(Clone, Copy, Debug, Default)]
pub(in crate::controller) struct HoldNoise {
    input: Option<RingInput>,
    last: [f32; 4],
    seen: u8,
    sum: f32,
    count: f32,
}

impl HoldNoise {
    /// Fewest differences the noise is told from.
    const MIN_COUNT: f32 = 32.0;

    /// A sample of `input` (another input than the last: heard afresh).
    pub(in crate::controller) fn observe(&mut self, input: RingInput, sample: f32) {
        if self.input != Some(input) {
            *self = Self {
                input: Some(input),
                ..Self::default()
            };
        }
        let [a, b, c, d] = self.last;
        if self.seen >= 4 {
            let fourth = a - 4.0 * b + 6.0 * c - 4.0 * d + sample;
            if fourth.is_finite() {
                self.sum += fourth * fourth;
                self.count += 1.0;
            }
        } else {
            self.seen += 1;
        }
        self.last = [b, c, d, sample];
    }

    /// Whether enough of the noise has been heard to tell it.
    pub(in crate::controller) fn heard(&self) -> bool {
        self.count >= Self::MIN_COUNT
    }

    /// The input heard and its noise's RMS a tick (none heard: `None`).
    pub(super) fn noise(&self) -> Option<(RingInput, f32)> {
        let input = self.input.filter(|_| self.heard())?;
        Some((input, libm::sqrtf(self.sum / (70.0 * self.count))))
    }
}

/// The tolerance a ring's measurement must meet: the trim's, or before a tracked drive the
/// tracker's reach.
pub(super) fn ring_tolerance(s: &Settings) -> f32 {
    let tolerance = s.trim_tolerance.unwrap_or(0.0);
    if s.track_seconds.is_some() {
        tolerance.max(TRACK_HANDOVER)
    } else {
        tolerance
    }
}

/// How long the trim's pulse lasts, ticks: half a target period in whole ticks.
pub(in crate::controller) fn pulse_ticks(s: &Settings) -> u32 {
    libm::roundf(0.5 * s.tick_hz / s.target_hz).max(1.0) as u32
}

/// The ring a trim's pulse at `bias_volts` leaves in the stretch (`RingGain`: undamped, an
/// upper bound), on `device` below `limit_offset`: what the AC starts on when the trim
/// converges (NaN where the bias has no equilibrium).
pub(in crate::controller) fn pulse_ring(
    device: &Device<f32>,
    limit_offset: f32,
    bias_volts: f32,
    s: &Settings,
) -> f32 {
    RingGain::at(device, limit_offset, bias_volts, pulse_seconds(s)).ring(
        RingInput::Stretch,
        bias_volts,
        s.trim_pulse_volts,
    )
}

/// How long the trim's pulse lasts, s.
pub(super) fn pulse_seconds(s: &Settings) -> f32 {
    pulse_ticks(s) as f32 / s.tick_hz
}

/// Half a period of a ring at `hz` in the window's samples (a stride of ticks each): the
/// high-pass's half span.
pub(super) fn half_samples(s: &Settings, hz: f32) -> usize {
    let (stride, _) = s.trim_window();
    libm::roundf(0.5 * s.tick_hz / (stride as f32 * hz)) as usize
}

/// The noise the image's front end declares for `input`, a tick (`None`: not read through
/// it).
pub(super) fn declared(inputs: InputNoise, input: RingInput) -> Option<f32> {
    match input {
        RingInput::Stretch => inputs.stretch,
        RingInput::Charge => inputs.amps,
    }
}

/// The ring a pulse at `bias_volts` would leave in `input`, the share `next` expects of the
/// undamped one over the share of the window it stands out of the noise in,
/// weighed against `noise` (a tick) by `RingFit::resolution` over the window (its periods
/// less the one the high-pass takes), and refused where below what the tolerance
/// needs. NaN figures (no prediction) say nothing.
pub(super) fn predicted(
    s: &Settings,
    (input, next): (RingInput, NextRing),
    bias_volts: f32,
    (noise, from): (f32, NoiseFrom),
) -> Option<TrimError> {
    let ring = next.seen * next.gain.ring(input, bias_volts, s.trim_pulse_volts);
    // No prediction (an unknown gain) says nothing; a noise that is no number leaves no
    // resolution (refused, not passed).
    if ring.is_nan() {
        return None;
    }
    let amplitude = input.in_window(ring, s.target_hz, s.tick_hz);
    let periods = s.trim_window_seconds * s.target_hz - 1.0;
    let resolution = if noise >= 0.0 {
        next.span * RingFit::resolution(amplitude, noise, s.tick_hz / s.target_hz, periods)
    } else {
        0.0
    };
    let needed = RingFit::needed(ring_tolerance(s));
    if resolution >= needed {
        return None;
    }
    Some(TrimError::Unresolvable {
        input,
        from,
        resolution,
        needed,
        ring,
        noise,
    })
}

/// The error for a shear modulus outside the batch's range `batch` (none without a batch).
pub(super) fn outside_batch(batch: Option<(f32, f32)>, shear_modulus: f32) -> Option<TrimError> {
    let (low, high) = batch?;
    (!(low <= shear_modulus && shear_modulus <= high)).then_some(TrimError::OutsideBatch {
        shear_modulus,
        low,
        high,
    })
}
