//! The controller's closed-loop trim (feature `trim`) as request and response, so that the
//! tick never solves: the tick pulses the bias and records the ring; at the window's end it
//! holds the bias and hands out a `TrimJob` (a copy of everything the solve needs); a
//! low-priority caller runs `TrimJob::solve` (the ring's frequency, μ re-estimated, the next
//! bias: `crate::estimate::ring`, `crate::tuning`) and gives the `TrimResult` back; a later tick
//! applies it.

use super::envelope::Predicted;
use super::fault::Fault;
use super::settings::{guarded, Settings, MAX_TRIMS, TRIM_SECANT_STEP};
use super::watch::Ring;
use super::{Controller, Event, State};
use crate::acquire::InputNoise;
use crate::estimate::ring::{
    estimate_shear_modulus, high_passed, model_hz, ring_frequency_hz, ring_share, ring_span,
    NoiseFrom, RingFit, RingGain, RingInput, RingQuality, TrimError, MAX_WINDOW,
    TIMING_ERROR_TIMES_RESOLUTION,
};
use crate::model::device::{Device, DeviceParams};
use crate::model::swing::{AcDrive, Ramp, Resonance, SwingError};
use crate::tuning::{TuneError, Tuner};

/// The relative frequency error at which the trim before a tracked drive hands over to the
/// tracker.
pub const TRACK_HANDOVER: f32 = 0.05;

/// The trim's memory between ticks: the model as estimated so far, the secant's last
/// point, and the window being measured.
#[derive(Clone, Debug)]
pub(super) struct TrimState {
    /// The device as estimated (μ re-estimated; the rest as told).
    pub(super) params: DeviceParams<f32>,
    /// Whether the bias held is the one the estimate gives for the target (not the probe).
    pub(super) tuned: bool,
    /// Trims done since the last convergence.
    pub(super) count: u8,
    /// The last measurement: (bias², measured f), for the secant step.
    pub(super) previous: Option<(f32, f32)>,
    /// The first tick of the window, and in it the input's running sum at each stride's
    /// last tick (NaN: no sample yet).
    pub(super) window_from: u32,
    pub(super) window: [f32; MAX_WINDOW],
    /// The ring input's running sum over the window: the current's (its charge, A·ticks),
    /// or the stretch's less its first sample (stretch·ticks).
    pub(super) sum: f32,
    /// The window's first stretch sample, and its last (NaN: none yet).
    pub(super) origin: f32,
    pub(super) last: f32,
    /// Whether the window holds that charge (no displacement sensor).
    pub(super) from_charge: bool,
    /// What the next pulse's ring is expected to be (`NextRing`).
    pub(super) ring: NextRing,
    /// The ring input's noise heard in the hold before it: with these two the tick says
    /// before it pulses whether the ring can be timed.
    pub(super) hold_noise: HoldNoise,
    /// The solve's answer, once the caller has given it.
    pub(super) result: Option<TrimResult>,
    /// Whether the answer's estimate (a `Retune`'s device) is the device flashed but for μ:
    /// worked out by `trim_done`, outside the tick.
    pub(super) result_shares_terms: bool,
    /// Whether the job wanted now was handed out.
    pub(super) handed_out: bool,
    /// The number of the job wanted now (`TrimDone::job`): a result of another is stale.
    pub(super) job: u32,
    /// A tracked drive's measured natural frequency, Hz, whose retune is wanted (instead of
    /// a window's ring).
    pub(super) tracked_hz: Option<f32>,
    /// The tracker's Q with it (NaN: none): the damping the drive's swing is checked with.
    pub(super) tracked_quality: f32,
    /// The last window's ring: its frequency, Hz, and Q (`None` before any).
    pub(super) ring_quality: Option<(f32, RingQuality)>,
}

impl TrimState {
    pub(super) fn new(params: DeviceParams<f32>, tuned: bool) -> Self {
        Self {
            params,
            tuned,
            count: 0,
            previous: None,
            window_from: 0,
            window: [f32::NAN; MAX_WINDOW],
            sum: 0.0,
            origin: f32::NAN,
            last: f32::NAN,
            from_charge: false,
            ring: NextRing::UNKNOWN,
            hold_noise: HoldNoise::default(),
            result: None,
            result_shares_terms: false,
            handed_out: false,
            job: 0,
            tracked_hz: None,
            tracked_quality: f32::NAN,
            ring_quality: None,
        }
    }

    /// A new job is wanted (a window measured, a tracked frequency to solve at): a result of
    /// any job handed out before is stale from now on.
    pub(super) fn want_job(&mut self, tracked: Option<(f32, f32)>) {
        self.job = self.job.wrapping_add(1);
        self.handed_out = false;
        self.result = None;
        self.tracked_hz = tracked.map(|(hz, _)| hz);
        self.tracked_quality = tracked.map_or(f32::NAN, |(_, q)| q);
    }

    /// Start afresh on a new plan (the trim's own μ, the window, the secant's history and
    /// the noise heard dropped, as at boot; the controller's estimated device and its cap
    /// stay), in place; the job wanted is dropped, its number kept counting so that a result
    /// of the old plan's is stale.
    pub(super) fn restart(&mut self, params: DeviceParams<f32>) {
        self.params = params;
        self.tuned = true;
        self.count = 0;
        self.previous = None;
        self.window_from = 0;
        self.window.fill(f32::NAN);
        self.sum = 0.0;
        self.origin = f32::NAN;
        self.last = f32::NAN;
        self.from_charge = false;
        self.ring = NextRing::UNKNOWN;
        self.hold_noise = HoldNoise::default();
        self.drop_job();
    }

    /// No job is wanted: a result of one handed out is dropped when it comes.
    pub(super) fn drop_job(&mut self) {
        self.want_job(None);
    }
}

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
pub(super) struct HoldNoise {
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
    pub(super) fn observe(&mut self, input: RingInput, sample: f32) {
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
    pub(super) fn heard(&self) -> bool {
        self.count >= Self::MIN_COUNT
    }

    /// The input heard and its noise's RMS a tick (none heard: `None`).
    fn noise(&self) -> Option<(RingInput, f32)> {
        let input = self.input.filter(|_| self.heard())?;
        Some((input, libm::sqrtf(self.sum / (70.0 * self.count))))
    }
}

/// The tolerance a ring's measurement must meet: the trim's, or before a tracked drive the
/// tracker's reach.
fn ring_tolerance(s: &Settings) -> f32 {
    let tolerance = s.trim_tolerance.unwrap_or(0.0);
    if s.track_seconds.is_some() {
        tolerance.max(TRACK_HANDOVER)
    } else {
        tolerance
    }
}

/// How long the trim's pulse lasts, ticks: half a target period in whole ticks.
pub(super) fn pulse_ticks(s: &Settings) -> u32 {
    libm::roundf(0.5 * s.tick_hz / s.target_hz).max(1.0) as u32
}

/// The ring a trim's pulse at `bias_volts` leaves in the stretch (`RingGain`: undamped, an
/// upper bound), on `device` below `limit_offset`: what the AC starts on when the trim
/// converges (NaN where the bias has no equilibrium).
pub(super) fn pulse_ring(
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
fn half_samples(s: &Settings, hz: f32) -> usize {
    let (stride, _) = s.trim_window();
    libm::roundf(0.5 * s.tick_hz / (stride as f32 * hz)) as usize
}

/// The noise the image's front end declares for `input`, a tick (`None`: not read through
/// it).
fn declared(inputs: InputNoise, input: RingInput) -> Option<f32> {
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
fn predicted(
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

impl TrimState {
    /// Before any voltage (at boot, at `target`): what the first pulse's ring will be at
    /// `bias_volts` on the device flashed (`NextRing::planned`), and a refusal where it
    /// cannot be timed to the tolerance against the noise the image's front end declares for
    /// the input the trim will time it in (the stretch where a sensor is read through it,
    /// else the current). Nothing to refuse where neither is declared.
    pub(super) fn plan_ring(
        &mut self,
        (device, limit_offset, bias_volts, s): (&Device<f32>, f32, f32, &Settings),
        inputs: InputNoise,
    ) -> Option<TrimError> {
        let declared = match (inputs.stretch, inputs.amps) {
            (Some(noise), _) => Some((RingInput::Stretch, noise)),
            (None, Some(noise)) => Some((RingInput::Charge, noise)),
            (None, None) => None,
        };
        let (input, noise) = declared.unwrap_or((RingInput::Stretch, 0.0));
        // The crossings' band for that noise, a window's sample summing a stride of ticks.
        let (stride, _) = s.trim_window();
        let per_sample = libm::sqrtf(stride as f32);
        let band = RingFit::band_of(noise * per_sample, half_samples(s, s.target_hz));
        self.ring = NextRing::planned(device, limit_offset, (bias_volts, s), (input, band));
        let (input, noise) = declared?;
        predicted(s, (input, self.ring), bias_volts, (noise, NoiseFrom::Image))
    }

    /// Before the pulse at `bias_volts`: the same, against the larger of the noise heard in
    /// the hold and the one declared (the one rule, checked again). Nothing to say before any
    /// noise is heard.
    pub(super) fn unresolvable(
        &self,
        s: &Settings,
        bias_volts: f32,
        inputs: InputNoise,
    ) -> Option<TrimError> {
        let (input, heard) = self.hold_noise.noise()?;
        let noise = match declared(inputs, input) {
            Some(floor) if floor > heard => (floor, NoiseFrom::Image),
            _ => (heard, NoiseFrom::Hold),
        };
        predicted(s, (input, self.ring), bias_volts, noise)
    }
}

/// A trim's work, handed out by `Controller::trim_job`: solved outside the tick.
#[derive(Clone, Debug)]
pub struct TrimJob {
    window: [f32; MAX_WINDOW],
    len: usize,
    settings: Settings,
    params: DeviceParams<f32>,
    bias_volts: f32,
    tuned: bool,
    count: u8,
    previous: Option<(f32, f32)>,
    /// The cap in force when the job was made, V: the result never goes above it.
    cap_volts: f32,
    /// Whether the window holds the charge (high-passed before its crossings are found).
    from_charge: bool,
    /// The noise the image's front end declares for the inputs (the floor of the window's).
    inputs: InputNoise,
    /// What the window before showed of the ring (`TrimState::ring`).
    ring: NextRing,
    /// Measured by the tracker (the window is not read), Hz, and its Q (NaN: none).
    measured_hz: Option<f32>,
    quality_factor: f32,
    /// Its number, carried by its result.
    job: u32,
    /// The batch's shear modulus range, Pa (model.md §10): an estimate outside it is said
    /// before any retune is solved from it.
    batch_modulus: Option<(f32, f32)>,
}

/// A job's result, for `Controller::trim_done`: taken only if the job is still the one
/// wanted (a late result of an older job is dropped).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrimDone {
    /// The job it answers.
    pub job: u32,
    pub result: TrimResult,
}

/// What a trim's solve found, given back by `Controller::trim_done`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrimResult {
    /// The measured frequency is the target's within the tolerance, at a tuned bias.
    Converged {
        measured_hz: f32,
        shear_modulus: f32,
        resolution: Option<f32>,
        /// The ring's Q, from its decay over the window (`None`: a tracked drive's solve).
        quality: Option<RingQuality>,
        /// The drive's swing from the bias on the ring the window heard (`None`: no AC).
        predicted: Option<Predicted>,
    },
    /// Ramp to `bias_volts` and measure again; `max_volts` is the estimate's own cap (the
    /// controller takes the lowest of it and the caps in force); `device` is the estimate
    /// (built here, not in the tick), `ring` what its next pulse's ring is expected to be.
    Retune {
        measured_hz: f32,
        shear_modulus: f32,
        bias_volts: f32,
        max_volts: f32,
        ring: NextRing,
        resolution: Option<f32>,
        /// The ring's Q, as `Converged`'s.
        quality: Option<RingQuality>,
        device: Device<f32>,
        /// The drive's swing at the new bias, as the estimate predicts it (`None`: no AC).
        predicted: Option<Predicted>,
    },
    /// The estimate needs `needed_volts` (bias and AC) above the lower of the cap in force
    /// and its own cap `max_volts` (which the controller takes as Retune's): hold.
    AboveCeiling {
        measured_hz: f32,
        shear_modulus: f32,
        needed_volts: f32,
        max_volts: f32,
    },
    /// No ring, no estimate, no convergence, or no safe bias: a fault.
    Failed(Fault),
}

impl TrimJob {
    /// The job for the window in `state`, measured at `bias_volts`, on inputs that declare
    /// `inputs`.
    pub(super) fn new(
        state: &TrimState,
        settings: Settings,
        (bias_volts, cap_volts): (f32, f32),
        inputs: InputNoise,
        batch_modulus: Option<(f32, f32)>,
    ) -> Self {
        Self {
            window: state.window,
            len: settings.trim_window().1,
            settings,
            params: state.params,
            bias_volts,
            tuned: state.tuned,
            count: state.count,
            previous: state.previous,
            cap_volts,
            from_charge: state.from_charge,
            inputs,
            ring: state.ring,
            measured_hz: state.tracked_hz,
            quality_factor: state.tracked_quality,
            job: state.job,
            batch_modulus,
        }
    }

    /// The ring's frequency, μ re-estimated so that the model gives it at the bias, and the
    /// next step: converged, or the next bias (by the secant through the last two
    /// measurements in (Φ², f) once there are two, each step at most `TRIM_SECANT_STEP` of
    /// the bias; else the estimated device's bias for the target), under the lower of the
    /// estimate's cap and the cap in force.
    pub fn solve(&self) -> TrimDone {
        let result = match self.try_solve() {
            Ok(result) => result,
            Err(fault) => TrimResult::Failed(fault),
        };
        TrimDone {
            job: self.job,
            result,
        }
    }

    fn try_solve(&self) -> Result<TrimResult, Fault> {
        let s = self.settings;
        let window = self.window.get(..self.len).unwrap_or(&self.window);
        // Before a tracked drive, the ring's trim need only bring the resonance within the
        // tracker's reach: the tracker holds the target with the drive on.
        let tolerance = match self.measured_hz {
            Some(_) => s.trim_tolerance.unwrap_or(0.0),
            None => ring_tolerance(&s),
        };
        // What the timing may be off by, relative,
        // and the resolution that says so.
        let mut timing_error = 0.0;
        let mut resolution = None;
        // The ring seen against the one the statics gave for this bias: the plant's damping
        // and the window's settling, which the next pulse's reckoning then takes in.
        let (mut ring_seen, mut ring_span) = (self.ring.seen, self.ring.span);
        // The ring the window heard, in its input (the AC a trim pauses rings on in it: what
        // the drive then starts on).
        let mut heard_ring = None;
        // Its decay: the plant's Q (model.md §7), whatever the device file says.
        let mut quality = None;
        let measured_hz = match self.measured_hz {
            Some(hz) => hz,
            None => {
                let (stride, _) = s.trim_window();
                let sample_hz = s.tick_hz / stride as f32;
                let input = if self.from_charge {
                    RingInput::Charge
                } else {
                    RingInput::Stretch
                };
                // A period of the ring the model expects at the bias (the target's if none):
                // a mismatch of a few percent only scales the ring a little.
                let expected_hz = model_hz(&self.params, self.bias_volts);
                let hz = if expected_hz > 0.0 {
                    expected_hz
                } else {
                    s.target_hz
                };
                let half = half_samples(&s, hz).min(window.len());
                // The declared noise, a sample: the sum's steps over a stride of ticks.
                let per_sample = libm::sqrtf(stride as f32);
                let floor = declared(self.inputs, input).map_or(0.0, |noise| noise * per_sample);
                // Too weak a ring is said, not estimated from (a window with neither ring nor
                // noise has no ring to time: `NoRing`, below).
                let ring = RingFit::of(window, half, floor);
                let needed = RingFit::needed(tolerance);
                let heard = ring.amplitude > 0.0 || ring.noise > 0.0;
                // The sum's ring as the input's (C, stretch).
                let to_ring = 1.0 / input.in_window(1.0, hz, s.tick_hz);
                let refused = |resolution: f32| {
                    Fault::Trim(TrimError::Unresolvable {
                        input,
                        from: NoiseFrom::Window,
                        resolution,
                        needed,
                        ring: ring.amplitude * to_ring,
                        noise: ring.noise / per_sample,
                    })
                };
                if heard && !(ring.resolution >= needed) {
                    return Err(refused(ring.resolution));
                }
                // Timed where the ring stands out of the noise (`ring_frequency_hz`'s band and
                // its check of each half period): a ring that fades into the noise before
                // the window ends is resolved over the share it was timed in.
                let timing = ring_frequency_hz(
                    high_passed(window, half),
                    sample_hz,
                    ring.band(half),
                    half as f32,
                )
                .map_err(Fault::Trim)?;
                // And no more than the crossings' own scatter about their line says.
                let scattered = TIMING_ERROR_TIMES_RESOLUTION / timing.scatter;
                let timed = (ring.resolution * timing.span).min(scattered);
                if heard && !(timed >= needed) {
                    return Err(refused(timed));
                }
                let measured_hz = timing.hz;
                if timed.is_finite() {
                    timing_error = TIMING_ERROR_TIMES_RESOLUTION / timed;
                    resolution = Some(timed);
                }
                let predicted = self
                    .ring
                    .gain
                    .ring(input, self.bias_volts, s.trim_pulse_volts);
                let seen = ring.amplitude * to_ring / predicted;
                if seen > 0.0 && seen.is_finite() {
                    ring_seen = seen;
                }
                heard_ring = Some((input, ring.amplitude * to_ring));
                quality = Some(RingQuality::of(window, half, floor, sample_hz, timing.hz));
                ring_span = timing.span;
                measured_hz
            }
        };
        let shear_modulus = estimate_shear_modulus(&self.params, self.bias_volts, measured_hz)
            .map_err(Fault::Trim)?;
        if let Some(error) = outside_batch(self.batch_modulus, shear_modulus) {
            return Err(Fault::Trim(error));
        }
        let params = DeviceParams {
            shear_modulus,
            ..self.params
        };
        let device = Device::new(params).map_err(Fault::Device)?;
        let tuner = Tuner::new(device);
        let limit_offset = tuner.limit().at.offset;
        // The free ring the membrane carries now, in stretch (model.md §7): the window's, as
        // heard (a paused drive's and the pulse's together; 0 unheard or not a number).
        let carried_ring_stretch = heard_ring.map_or(0.0, |(input, ring)| {
            let gain = RingGain::at(&device, limit_offset, self.bias_volts, pulse_seconds(&s));
            let stretch = gain.stretch_of(input, self.bias_volts, ring);
            if stretch.is_finite() {
                stretch
            } else {
                0.0
            }
        });
        // On target when within the tolerance less twice the timing's error: then the
        // frequency itself is within it.
        let converged = self.tuned
            && (measured_hz - s.target_hz).abs() <= (tolerance - 2.0 * timing_error) * s.target_hz;
        if converged {
            // The AC starts at once on the ring heard (or the pulse's, if more). A tracked
            // drive's solve restarts nothing: its drive runs on.
            let pulse = pulse_ring(&device, limit_offset, self.bias_volts, &s);
            let predicted = match self.measured_hz {
                Some(_) => None,
                None => self.restart_swing(
                    (&device, limit_offset),
                    self.bias_volts,
                    (carried_ring_stretch.max(pulse), quality),
                    None,
                )?,
            };
            return Ok(TrimResult::Converged {
                measured_hz,
                shear_modulus,
                resolution,
                quality,
                predicted,
            });
        }
        if self.count.saturating_add(1) >= MAX_TRIMS {
            return Err(Fault::Trim(TrimError::NotConverged {
                measured_hz,
                target_hz: s.target_hz,
            }));
        }
        let margin = guarded(s.margin);
        // The estimate may lower the cap (a softer plant), never raise it past the cap in
        // force (the operator's, the ceiling, an earlier estimate's).
        let at_cap = tuner.max_bias(margin).map_err(Fault::Tune)?;
        let estimate_volts = at_cap.volts;
        let max_volts = estimate_volts.min(self.cap_volts);
        let from = self.bias_volts;
        let squared = from * from;
        // Tracking's solves take no secant: its two points, apart in time, differ by the
        // drift too (a plant that stiffened sent the secant, and the bias, the wrong way).
        let previous = self.previous.filter(|_| self.measured_hz.is_none());
        let secant = previous.and_then(|(p2, pf)| {
            let next = squared + (s.target_hz - measured_hz) * (squared - p2) / (measured_hz - pf);
            // No slope (two equal frequencies): the model decides.
            if !next.is_finite() {
                return None;
            }
            // A trust region: a drifting plant (creep) makes a poor secant, and a wild step
            // (past zero volts, or up) is what the model's region cannot vouch for.
            let step = TRIM_SECANT_STEP * from;
            let volts = libm::sqrtf(next.max(0.0)).clamp(from - step, from + step);
            (volts + s.swing_volts() <= max_volts).then_some(volts)
        });
        let bias_volts = match secant {
            Some(volts) => volts,
            None => match tuner.tune(s.target_hz, margin) {
                Ok(solved) => solved.volts,
                // Past the estimate's reach under the margin on the side more bias goes
                // (f falls with the bias on most devices, rises on some: model.md §5): the
                // target needs more than the cap (the bias for it at no margin, at least
                // the limit's), a hold that says so below, not a fault.
                Err(TuneError::OutOfRange { .. })
                    if (s.target_hz - at_cap.natural_frequency_hz)
                        * (at_cap.natural_frequency_hz
                            - tuner.zero_bias().natural_frequency_hz)
                        > 0.0 =>
                {
                    tuner
                        .tune(s.target_hz, 0.0)
                        .map_or(tuner.limit().at.volts, |solved| solved.volts)
                }
                Err(error) => return Err(Fault::Tune(error)),
            },
        };
        // A bias above the estimate's cap is no fault here: the controller takes the lower
        // cap and comes down to it at the slew rate (from where it is, `Plan::start_under`;
        // while tracking, a hold).
        let needed_volts = bias_volts + s.swing_volts();
        if !(needed_volts <= max_volts) {
            return Ok(TrimResult::AboveCeiling {
                measured_hz,
                shear_modulus,
                needed_volts,
                max_volts: estimate_volts,
            });
        }
        // The drive's swing at the new bias on the estimate (model.md §7), from the bias
        // measured at: the ring carried through the ramp and the next pulse's.
        let ring_stretch = pulse_ring(&device, limit_offset, bias_volts, &s) + carried_ring_stretch;
        let ramp = Ramp {
            from_volts: self.bias_volts,
            slew_volts_per_second: s.slew_volts_per_second,
            settle_seconds: match self.measured_hz {
                Some(_) => 0.0,
                None => s.settle_seconds,
            },
            after_descent: false,
        };
        let predicted = self.restart_swing(
            (&device, limit_offset),
            bias_volts,
            (ring_stretch, quality),
            Some(ramp),
        )?;
        Ok(TrimResult::Retune {
            measured_hz,
            shear_modulus,
            bias_volts,
            max_volts: estimate_volts,
            ring: NextRing {
                gain: RingGain::at(
                    &device,
                    tuner.limit().at.offset,
                    bias_volts,
                    pulse_seconds(&s),
                ),
                seen: ring_seen,
                span: ring_span,
            },
            resolution,
            quality,
            device,
            predicted,
        })
    }

    /// The swing of the drive the trim starts at `bias_volts` on the estimate `device` (below
    /// `limit_offset`), on a free ring of `ring_stretch` (after `ramp`, if any), checked
    /// (model.md §7) and predicted for the watch; `None` without AC. A tracked drive follows
    /// the resonance, so it is checked there, with the tracker's Q; else with the highest Q
    /// the window's ring allows (`ring_quality`), or the device's damping where it gives a
    /// higher Q or the ring bounds none.
    fn restart_swing(
        &self,
        (device, limit_offset): (&Device<f32>, f32),
        bias_volts: f32,
        (ring_stretch, ring_quality): (f32, Option<RingQuality>),
        ramp: Option<Ramp<f32>>,
    ) -> Result<Option<Predicted>, Fault> {
        let s = &self.settings;
        // A dead DAC bus's drop from the drive's top to 0 V at once, from rest there
        // (`Device::check_drop`; the boot's).
        let top_volts = bias_volts + s.swing_volts();
        device
            .check_drop(top_volts, 0.0, limit_offset, s.margin)
            .map_err(|e| Fault::of_drop(top_volts, e))?;
        if !(s.ac_volts > 0.0) {
            return Ok(None);
        }
        let natural_hz = device
            .offset_for_bias(bias_volts, limit_offset)
            .map_or(f32::NAN, |offset| device.natural_frequency_hz_at(offset));
        let quality = match self.measured_hz {
            Some(_) => (self.quality_factor > 0.0).then_some(self.quality_factor),
            None => ring_quality
                .map(|q| q.high)
                .filter(|high| high.is_finite())
                .map(|high| {
                    // The device's own Q at the bias (∞ undamped: the ring's then).
                    let p = device.params();
                    let told = p.effective_mass() * core::f32::consts::TAU * natural_hz / p.damping;
                    if told.is_finite() && told > high {
                        told
                    } else {
                        high
                    }
                }),
        };
        // A tracked drive (its solves, and the trims before it) at the resonance it follows.
        let tracked = self.measured_hz.is_some() || s.track_seconds.is_some();
        let ac_hz = if tracked && natural_hz > 0.0 {
            natural_hz
        } else {
            s.ac_hz
        };
        // No natural frequency at the bias (a fold): no swing to bound.
        if !(ac_hz > 0.0) {
            return Err(Fault::DriveSwing(SwingError::Unbounded {
                resonance: Resonance::Static,
                natural_hz: 0.0,
                quality_factor: self.quality_factor,
                largest_ac_volts: 0.0,
            }));
        }
        let drive = AcDrive {
            bias_volts,
            ac_volts: s.ac_volts,
            ac_hz,
            amplifier_bandwidth_hz: s.amplifier_bandwidth_hz.unwrap_or(f32::INFINITY),
            ring_stretch,
            ramp,
        };
        let swing = device
            .check_swing(drive, limit_offset, quality, s.margin)
            .map_err(Fault::DriveSwing)?;
        Ok(Some(Predicted::of(
            &swing,
            ac_hz,
            s.margin,
            self.inputs.stretch,
        )))
    }
}

/// The trim as the controller runs it: handing out the window's job, taking its result, and
/// the tick's steps of a trim (measure, record, pause, retune, apply).
impl Controller {
    /// The trim's job for the window just measured, once (`None` otherwise): run
    /// `TrimJob::solve` outside the tick (a low-priority task) and give its result to
    /// `trim_done`; the bias holds meanwhile.
    pub fn trim_job(&mut self) -> Option<TrimJob> {
        if !self.job_wanted() || self.trim.handed_out {
            return None;
        }
        self.trim.handed_out = true;
        let (bias, cap) = (self.plan.bias_volts, self.max_volts);
        Some(TrimJob::new(
            &self.trim,
            self.settings,
            (bias, cap),
            self.inputs,
            self.batch_modulus,
        ))
    }

    /// Whether a job waits to be handed out (`trim_job`): the window's solve, or tracking's
    /// slope while driving. What a firmware's tick asks before it wakes its work task.
    pub fn job_pending(&self) -> bool {
        self.job_wanted() && !self.trim.handed_out
    }

    /// Whether a job is wanted now: a measured window's solve, or tracking's slope.
    fn job_wanted(&self) -> bool {
        let tracking =
            matches!(self.state, State::Driving { .. }) && self.trim.tracked_hz.is_some();
        self.state == State::Solving || tracking
    }

    /// The result of the job handed out: the next tick applies it. A result of a job no
    /// longer wanted (late, or stale: the controller moved on), or a second result, is
    /// dropped.
    pub fn trim_done(&mut self, done: TrimDone) {
        let current = self.trim.handed_out && done.job == self.trim.job;
        if self.job_wanted() && current && self.trim.result.is_none() {
            // The estimate's comparison with the device flashed here, outside the tick.
            self.trim.result_shares_terms = match &done.result {
                TrimResult::Retune { device, .. } => {
                    // Into the spare slot, here (outside the tick): the tick that applies it
                    // turns to it.
                    let spare = 1 - self.estimate_at.min(1);
                    if let Some(slot) = self.estimates.get_mut(spare) {
                        *slot = Some(*device);
                    }
                    device.differs_only_in_modulus(&self.flashed)
                }
                _ => false,
            };
            self.trim.result = Some(done.result);
        }
    }

    /// Pulse now; measure the ring from the pulse's end. Not where the ring it would leave is
    /// too weak against the noise heard in the hold (or declared): that is said first.
    pub(super) fn start_measuring(&mut self, k: u32) -> Result<(), Fault> {
        let s = self.settings;
        if let Some(error) = self
            .trim
            .unresolvable(&s, self.plan.bias_volts, self.inputs)
        {
            return Err(Fault::Trim(error));
        }
        let pulse = pulse_ticks(&s);
        let from = k.saturating_add(1);
        self.plan.pulse_ticks = (from, from.saturating_add(pulse));
        self.plan.pulse_volts = s.trim_pulse_volts;
        // No clearing (512 stores): every tick of the window writes its slot.
        self.trim.window_from = from.saturating_add(pulse);
        self.trim.sum = 0.0;
        self.trim.origin = f32::NAN;
        self.trim.last = f32::NAN;
        self.trim.from_charge = false;
        // The probe's charge would swamp the ring's: off until the trim is applied.
        self.plan.probe_volts = 0.0;
        self.trim.drop_job();
        self.state = State::Measuring;
        Ok(())
    }

    /// Record this tick's sample; at the window's end, hand the solve out and bring the probe
    /// back (`Plan::probe_back`: a fault if it no longer fits). The ring is timed in its
    /// input's running sum: the current's is the charge (Q = C(λ)·Φ at a constant bias,
    /// model.md §8, so it follows λ), the stretch's carries its ring a quarter period on; the
    /// sum turns the input's noise into a slow wander, which the crossings' fit averages out,
    /// where the input's own crossings would multiply (`estimate::ring::RingFit`). From the
    /// current, the window's first tenth of a target period is skipped (NaN): the step back from the
    /// pulse charges the membrane then (C·dΦ/dt, far above the ring's Φ·C'·dλ/dt).
    pub(super) fn record(&mut self, k: u32, ring: Ring) -> Result<(), Fault> {
        let s = &self.settings;
        let (stride, len) = s.trim_window();
        let Some(at) = k.checked_sub(self.trim.window_from) else {
            return Ok(());
        };
        let settling = (0.1 * s.tick_hz / s.target_hz) as u32 + 1;
        // The window's input is its first sample's: a tick without a stretch sample in a
        // stretch window carries the last one (the sum goes on), and one input never mixes
        // into the other's sum.
        let stretch_window = !self.trim.origin.is_nan();
        let sample = match ring {
            Ring::Stretch(stretch) if stretch.is_finite() && !self.trim.from_charge => {
                if !stretch_window {
                    self.trim.origin = stretch;
                }
                self.trim.last = stretch;
                self.trim.sum += stretch - self.trim.origin;
                self.trim.sum
            }
            Ring::Current(amps) if at >= settling && !stretch_window => {
                self.trim.from_charge = true;
                self.trim.sum += amps;
                self.trim.sum
            }
            _ if stretch_window => {
                self.trim.sum += self.trim.last - self.trim.origin;
                self.trim.sum
            }
            Ring::Stretch(_) | Ring::Current(_) | Ring::Nothing => f32::NAN,
        };
        // The sum at each stride's last tick: its steps sum a stride of the input's ticks.
        if let Some(slot) = self.trim.window.get_mut((at / stride) as usize) {
            *slot = sample;
        }
        if at.saturating_add(1) >= stride.saturating_mul(len as u32) {
            self.state = State::Solving;
            self.plan
                .probe_back(s.probe_volts.unwrap_or(0.0), self.max_volts)?;
        }
        Ok(())
    }

    /// Pause the AC and trim again from the bias held (the old secant pair is stale: the
    /// plant has drifted since).
    pub(super) fn pause_for_trim(&mut self, k: u32) {
        self.trim.drop_job();
        // The bias held where the ramp is now (a tracked drive's last move may not be done):
        // the retune after the window ramps on from it.
        let here = self.plan.ramp_volts(k);
        self.plan.start_tick = k;
        self.plan.start_volts = here;
        self.plan.bias_volts = here;
        self.plan.ac_tick = None;
        self.trim.tuned = true;
        self.trim.count = 0;
        self.trim.previous = None;
        self.hold_from(k, true);
    }

    /// A `Retune`'s new plan at tick `k`: from `bias_volts` to `next_bias_volts` under the
    /// lower of its cap and the cap in force, checked; the estimate taken from the result
    /// (still waiting in `trim.result`). `(f, μ, the next ring)` the trim's memory.
    fn retune(
        &mut self,
        k: u32,
        bias_volts: f32,
        next_bias_volts: f32,
        max_volts: f32,
        (measured_hz, shear_modulus, ring): (f32, f32, NextRing),
    ) -> Result<(), Fault> {
        self.trim.params.shear_modulus = shear_modulus;
        self.trim.count = self.trim.count.saturating_add(1);
        self.trim.ring = ring;
        self.trim.previous = Some((bias_volts * bias_volts, measured_hz));
        // The new plan built in place (the tick's budget: a plan is large), the fields it
        // changes restored if a check refuses it.
        let plan = &mut self.plan;
        let before = (
            plan.start_tick,
            plan.start_volts,
            plan.bias_volts,
            plan.pulse_ticks,
            plan.probe_volts,
        );
        // From the bias held since the ramp reached it (a window is measured only at the
        // bias: `State::Holding` follows the ramp's end), at the slew rate.
        plan.start_tick = k.saturating_add(1);
        plan.start_volts = bias_volts;
        plan.bias_volts = next_bias_volts;
        plan.pulse_ticks = (0, 0);
        let bound = max_volts.min(self.max_volts);
        plan.start_under(bound, self.last_volts);
        let checked = plan.check_range(next_bias_volts, bound).and_then(|()| {
            plan.probe_off_above(bound);
            self.amplifier
                .code(next_bias_volts + plan.swing_volts())
                .map(|_| ())
                .map_err(Fault::Amplifier)
        });
        if let Err(fault) = checked {
            (
                plan.start_tick,
                plan.start_volts,
                plan.bias_volts,
                plan.pulse_ticks,
                plan.probe_volts,
            ) = before;
            return Err(fault);
        }
        self.take_estimate_cap(max_volts);
        self.take_estimate();
        self.trim.tuned = true;
        self.state = State::Ramping { then_measure: true };
        Ok(())
    }

    /// A result that needs more than the cap in force: the estimate's μ and cap taken, the
    /// bias held where it is, and said (`Event::AboveCeiling`).
    pub(super) fn hold_below_ceiling(
        &mut self,
        k: u32,
        shear_modulus: f32,
        needed_volts: f32,
        max_volts: f32,
    ) -> Event {
        self.trim.params.shear_modulus = shear_modulus;
        self.take_estimate_cap(max_volts);
        self.hold(k, needed_volts)
    }

    /// A trim's result whose μ lies outside the batch the table was made for (model.md §10):
    /// the fault that says so (checked here too: a result is given back from outside the
    /// tick). A measurement never widens the batch, nor raises the cap past its own.
    pub(super) fn outside_batch(&self, result: &TrimResult) -> Option<Fault> {
        let shear_modulus = match *result {
            TrimResult::Converged { shear_modulus, .. }
            | TrimResult::Retune { shear_modulus, .. }
            | TrimResult::AboveCeiling { shear_modulus, .. } => shear_modulus,
            TrimResult::Failed(_) => return None,
        };
        outside_batch(self.batch_modulus, shear_modulus).map(Fault::Trim)
    }

    /// Apply the trim's result at tick `k`, once it has come back.
    pub(super) fn apply_trim(&mut self, k: u32) -> Result<Option<Event>, Fault> {
        // Read in place (a `Retune` holds a device, large: copied once, into the estimate).
        let Some(result) = &self.trim.result else {
            return Ok(None);
        };
        if let Some(fault) = self.outside_batch(result) {
            self.trim.result = None;
            return Err(fault);
        }
        let bias_volts = self.plan.bias_volts;
        let result = match *result {
            TrimResult::Retune {
                measured_hz,
                shear_modulus,
                bias_volts: next_bias_volts,
                max_volts,
                ring,
                resolution,
                quality,
                predicted,
                ..
            } => {
                if predicted.is_some() {
                    self.watch.predict(predicted);
                }
                self.trim.ring_quality = quality.map(|q| (measured_hz, q));
                let applied = self.retune(
                    k,
                    bias_volts,
                    next_bias_volts,
                    max_volts,
                    (measured_hz, shear_modulus, ring),
                );
                self.trim.result = None;
                applied?;
                return Ok(Some(Event::Trimmed {
                    bias_volts,
                    measured_hz,
                    shear_modulus,
                    next_bias_volts,
                    resolution,
                    quality,
                }));
            }
            _ => self.trim.result.take(),
        };
        let Some(result) = result else {
            return Ok(None);
        };
        match result {
            TrimResult::Converged {
                measured_hz,
                shear_modulus,
                resolution,
                quality,
                predicted,
            } => {
                self.trim.params.shear_modulus = shear_modulus;
                self.trim.ring_quality = quality.map(|q| (measured_hz, q));
                if predicted.is_some() {
                    self.watch.predict(predicted);
                }
                self.trim.count = self.trim.count.saturating_add(1);
                // The AC from phase 0, as the swing's check has it switched on.
                self.plan.ac_tick = Some(k.saturating_add(1));
                self.plan.ac_phase_start = 0;
                self.state = State::Holding {
                    until: k,
                    then_measure: false,
                };
                Ok(Some(Event::Trimmed {
                    bias_volts,
                    measured_hz,
                    shear_modulus,
                    next_bias_volts: bias_volts,
                    resolution,
                    quality,
                }))
            }
            // Taken above.
            TrimResult::Retune { .. } => Ok(None),
            TrimResult::AboveCeiling {
                shear_modulus,
                needed_volts,
                max_volts,
                ..
            } => Ok(Some(self.hold_below_ceiling(
                k,
                shear_modulus,
                needed_volts,
                max_volts,
            ))),
            // A ring too weak to time in the window, on a membrane that may carry a ring of
            // its own (a drive ran since the last plan without AC: paused, or before a new
            // plan's ramp): that ring can meet the pulse's out of phase. Measured again from a
            // hold (the next pulse meets it elsewhere in its phase), within `MAX_TRIMS`.
            TrimResult::Failed(Fault::Trim(TrimError::Unresolvable {
                from: NoiseFrom::Window,
                ..
            })) if self.watch.ring_to_carry_stretch() > 0.0
                && self.trim.count.saturating_add(1) < MAX_TRIMS =>
            {
                self.trim.count = self.trim.count.saturating_add(1);
                self.hold_from(k, true);
                Ok(None)
            }
            TrimResult::Failed(fault) => Err(fault),
        }
    }
}

/// The error for a shear modulus outside the batch's range `batch` (none without a batch).
fn outside_batch(batch: Option<(f32, f32)>, shear_modulus: f32) -> Option<TrimError> {
    let (low, high) = batch?;
    (!(low <= shear_modulus && shear_modulus <= high)).then_some(TrimError::OutsideBatch {
        shear_modulus,
        low,
        high,
    })
}

#[cfg(test)]
#[allow(clippy::panic)] // a test fails by panicking
mod tests {
    use super::*;
    use crate::model::device::REFERENCE_DEVICE;

    /// A job for the reference device measured at `bias_volts`, its window a clean ring at
    /// `ring_hz` (500 ticks at 1 kHz), with a previous measurement `previous`.
    fn job(bias_volts: f32, ring_hz: f32, previous: Option<(f32, f32)>) -> TrimJob {
        let settings = Settings {
            trim_tolerance: Some(1e-3),
            ..Settings::for_target(44.0)
        };
        let mut window = [f32::NAN; MAX_WINDOW];
        for (k, slot) in window.iter_mut().enumerate().take(500) {
            let t = k as f32 / 1000.0;
            *slot = 2.2 + 1e-3 * libm::sinf(core::f32::consts::TAU * ring_hz * t + 0.3);
        }
        TrimJob {
            window,
            len: 500,
            settings,
            params: REFERENCE_DEVICE.cast(),
            bias_volts,
            tuned: true,
            count: 1,
            previous,
            cap_volts: 9361.9,
            from_charge: false,
            inputs: InputNoise::UNDECLARED,
            ring: NextRing::UNKNOWN,
            measured_hz: None,
            quality_factor: f32::NAN,
            job: 0,
            batch_modulus: None,
        }
    }

    fn retune_bias(done: TrimDone) -> f32 {
        match done.result {
            TrimResult::Retune { bias_volts, .. } => bias_volts,
            other => panic!("{other:?}"),
        }
    }

    /// The secant in (Φ², f) through the last two measurements, clamped to ±10% of the bias:
    /// here it would ask for 10.7 kV from 5 kV (up), and for a negative Φ² (down).
    #[test]
    fn the_secant_step_is_at_most_a_tenth_of_the_bias() {
        // f falls 0.1 Hz from 4 kV to 5 kV; 1 Hz more to go: Φ² up by 9·10⁷ V².
        let up = job(5000.0, 45.0, Some((4000.0 * 4000.0, 45.1)));
        assert!((retune_bias(up.solve()) / 5500.0 - 1.0).abs() < 1e-6);
        // f at 43 Hz, the target 1 Hz up, the slope as steep: Φ² down past zero.
        let down = job(5000.0, 43.0, Some((4000.0 * 4000.0, 43.1)));
        assert!((retune_bias(down.solve()) / 4500.0 - 1.0).abs() < 1e-6);
    }

    /// A secant step that would take the bias and its AC past the cap is not taken: the
    /// estimated model decides. Here it needs more than the cap too, so the trim holds and
    /// says what the model needs, not what the rejected secant asked (9350 V + 300 V).
    #[test]
    fn a_secant_past_the_cap_falls_back_to_the_model() {
        // 44.5 Hz at 8.5 kV, 44.55 at 8.3 kV: the secant asks 10.3 kV, clamped to 9350 V,
        // whose 300 V of AC would pass the 9361.9 V cap.
        let mut near = job(8500.0, 44.5, Some((8300.0 * 8300.0, 44.55)));
        near.settings.ac_volts = 300.0;
        match near.solve().result {
            TrimResult::AboveCeiling { needed_volts, .. } => {
                assert!(needed_volts > 9361.9 && (needed_volts - 9650.0).abs() > 1.0);
            }
            other => panic!("{other:?}"),
        }
    }

    /// A ring that tells of a plant so stiff that the target is below its reach under the
    /// margin (47 Hz at 3 kV, 44 Hz asked; the reference device gives 45.6 Hz there): the
    /// trim holds and says what the plant needs (the estimate's bias for the target at no
    /// margin, from an f64 solve of the device whose μ gives 47 Hz at 3 kV, found by
    /// bisection here), not a tuning fault that latches at zero volts.
    #[test]
    #[allow(clippy::unwrap_used)] // a test fails by panicking
    fn a_target_past_the_estimates_reach_is_a_hold() {
        use crate::tuning::Tuner;
        let stiff_hz = |mu: f64| {
            let device = Device::new(DeviceParams {
                shear_modulus: mu,
                ..REFERENCE_DEVICE
            })
            .unwrap();
            let limit = *Tuner::new(device).limit();
            let offset = device.offset_for_bias(3000.0, limit.at.offset).unwrap();
            device.natural_frequency_hz_at(offset)
        };
        let (mut low, mut high) = (
            REFERENCE_DEVICE.shear_modulus,
            2.0 * REFERENCE_DEVICE.shear_modulus,
        );
        for _ in 0..60 {
            let mid = 0.5 * (low + high);
            if stiff_hz(mid) < 47.0 {
                low = mid;
            } else {
                high = mid;
            }
        }
        let stiff = Device::new(DeviceParams {
            shear_modulus: low,
            ..REFERENCE_DEVICE
        })
        .unwrap();
        let tuner = Tuner::new(stiff);
        assert!(
            tuner.tune(44.0, 0.05).is_err(),
            "the target is within reach"
        );
        let needs = tuner.tune(44.0, 0.0).unwrap().volts;
        match job(3000.0, 47.0, None).solve().result {
            TrimResult::AboveCeiling { needed_volts, .. } => {
                let expected = needs + f64::from(Settings::for_target(44.0).swing_volts());
                assert!(
                    (f64::from(needed_volts) / expected - 1.0).abs() < 1e-3,
                    "{needed_volts} V, {expected} V"
                );
            }
            other => panic!("{other:?}"),
        }
    }

    /// A ring that tells of a plant so soft that the target lies above its frequency at no
    /// bias (40 Hz at 3 kV where the reference device gives 45.6 Hz, 44 Hz asked): no bias
    /// reaches it, more or less, so a tuning fault whose range tops out under 44 Hz, not a
    /// hold.
    #[test]
    fn a_target_no_bias_reaches_is_a_fault() {
        match job(3000.0, 40.0, None).solve().result {
            TrimResult::Failed(Fault::Tune(TuneError::OutOfRange { high_hz, .. })) => {
                assert!(high_hz < 44.0, "{high_hz}");
            }
            other => panic!("{other:?}"),
        }
    }

    /// Tracking's solves (a measured frequency handed in) take no secant: the previous point
    /// is from another time, and the plant drifted since. With one or without, the same.
    #[test]
    fn a_tracked_solve_takes_no_secant() {
        let tracked = |previous| TrimJob {
            measured_hz: Some(44.3),
            ..job(4000.0, 44.3, previous)
        };
        let with = retune_bias(tracked(Some((3000.0 * 3000.0, 45.9))).solve());
        let without = retune_bias(tracked(None).solve());
        assert_eq!(with, without);
        // And a ring trim with that point does take it: the point matters.
        let ring = retune_bias(job(4000.0, 44.3, Some((3000.0 * 3000.0, 45.9))).solve());
        assert_ne!(ring, without);
    }

    /// A μ outside the batch's range, or NaN, is the batch's fault; inside it, or with no
    /// batch, none.
    #[test]
    fn a_modulus_outside_the_batch_is_said() {
        let batch = Some((40.5e3, 49.5e3));
        for mu in [40.5e3, 45e3, 49.5e3] {
            assert_eq!(outside_batch(batch, mu), None);
        }
        for mu in [40.4e3, 49.6e3, f32::NAN, 0.0] {
            assert!(matches!(
                outside_batch(batch, mu),
                Some(TrimError::OutsideBatch { low, high, .. }) if (low, high) == (40.5e3, 49.5e3)
            ));
        }
        assert_eq!(outside_batch(None, 1.0), None);
    }
}
