//! The controller's closed-loop trim (feature `trim`) as request and response, so that the
//! tick never solves: the tick pulses the bias and records the ring; at the window's end it
//! holds the bias and hands out a `TrimJob` (a copy of everything the solve needs); a
//! low-priority caller runs `TrimJob::solve` (the ring's frequency, μ re-estimated, the next
//! bias: `crate::estimate::ring`, `crate::tuning`) and gives the `TrimResult` back; a later tick
//! applies it.

mod job;
mod ring;

use super::fault::Fault;
use super::settings::{Settings, MAX_TRIMS};
use super::watch::Ring;
use super::{Controller, Event, State};
use crate::acquire::InputNoise;
use crate::estimate::ring::{NoiseFrom, RingFit, RingInput, RingQuality, TrimError, MAX_WINDOW};
use crate::model::device::{Device, DeviceParams};
pub use job::{Ceiling, TrimDone, TrimJob, TrimResult};
pub use ring::NextRing;
use ring::{declared, half_samples, outside_batch, predicted};
pub(super) use ring::{pulse_ring, pulse_ticks, HoldNoise};

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
    /// A trim at boot. The window is made zero and then NaN in place: a NaN array in the
    /// literal was built on the stack and copied (1.7 KB more of the firmware's boot stack).
    pub(super) fn new(params: DeviceParams<f32>, tuned: bool) -> Self {
        let mut state = Self {
            params,
            tuned,
            count: 0,
            previous: None,
            window_from: 0,
            window: [0.0; MAX_WINDOW],
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
        };
        state.window.fill(f32::NAN);
        state
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

impl TrimJob {
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
    pub(super) fn hold_below_ceiling(&mut self, k: u32, ceiling: Ceiling) -> Event {
        self.trim.params.shear_modulus = ceiling.shear_modulus;
        self.take_estimate_cap(ceiling.max_volts);
        self.hold(k, ceiling.needed_volts)
    }

    /// A trim's result whose μ lies outside the batch the table was made for (model.md §10):
    /// the fault that says so (checked here too: a result is given back from outside the
    /// tick). A measurement never widens the batch, nor raises the cap past its own.
    fn outside_batch(&self, result: &TrimResult) -> Option<Fault> {
        let shear_modulus = match *result {
            TrimResult::Converged { shear_modulus, .. }
            | TrimResult::Retune { shear_modulus, .. }
            | TrimResult::AboveCeiling(Ceiling { shear_modulus, .. }) => shear_modulus,
            TrimResult::Failed(_) => return None,
        };
        outside_batch(self.batch_modulus, shear_modulus).map(Fault::Trim)
    }

    /// The solve's result once it has come back (`None` before), read in place (a `Retune`
    /// holds a device, large: copied once, into the estimate); one whose μ lies outside the
    /// batch is dropped for its fault. The first step of every use of a result.
    pub(super) fn checked_result(&mut self) -> Result<Option<&TrimResult>, Fault> {
        let Some(result) = &self.trim.result else {
            return Ok(None);
        };
        if let Some(fault) = self.outside_batch(result) {
            self.trim.result = None;
            return Err(fault);
        }
        Ok(self.trim.result.as_ref())
    }

    /// Apply the trim's result at tick `k`, once it has come back.
    pub(super) fn apply_trim(&mut self, k: u32) -> Result<Option<Event>, Fault> {
        let bias_volts = self.plan.bias_volts;
        let Some(result) = self.checked_result()? else {
            return Ok(None);
        };
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
            TrimResult::AboveCeiling(ceiling) => Ok(Some(self.hold_below_ceiling(k, ceiling))),
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
