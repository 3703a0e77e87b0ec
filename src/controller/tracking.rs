//! Resonance tracking while driving (feature `track`): each tick of a tracked drive feeds
//! the stretch to `crate::estimate::lockin::Tracker`; at each cycle's end the drive follows the
//! resonance (in phase) and the bias moves by an integral law on the frequency error, its
//! gain the model's slope dΦ²/df, which the trim's solve gives outside the tick (`TrimJob`
//! with the measured frequency) now and then.

use super::fault::Fault;
use super::trim::TrimResult;
use super::watch::Ring;
use super::{Controller, Event};
use crate::estimate::lockin::{drive_force_per_stretch, Lock, Tracker, MAX_DETUNING};
use crate::numerics::real::sqrt_f32;

/// The tracker's memory between ticks.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Tracking {
    /// The tracker, once the tracked drive has a sample.
    pub(super) tracker: Option<Tracker>,
    /// The tick the settling counts from: the drive's first sample, or the last cycle whose
    /// drive was off the resonance it measured.
    pub(super) steady_from: u32,
    /// The model's dΦ²/df at the bias, V²/Hz, once a solve has given it.
    pub(super) volts_squared_per_hz: Option<f32>,
    /// The tick of the last solve asked for, once one was.
    pub(super) solved_at: Option<u32>,
    /// The last cycle's fit, applied on the tick after it.
    pub(super) to_apply: Option<Lock>,
    /// The fit's force per stretch and gain, worked out on the tick after its cycle was set
    /// aside (`None` until then).
    pub(super) fit_inputs: Option<(f32, f32)>,
}

/// Time constants of the tracker the estimate waits before the bias moves on it.
const SETTLE_TIME_CONSTANTS: f32 = 3.0;

/// The drive is settled on the resonance when it is within this fraction of the resonance's
/// half-width f/(2Q) of the cycle's estimate (about 6° of phase); until then the estimate
/// is of a plant still ring_stretch from the drive's moves, and the settling starts again. (A
/// creeping plant's drive follows the resonance within it; measured from where the drive
/// was instead, the settling never ended on the VHB plant.)
const SETTLED_HALF_WIDTHS: f32 = 0.1;

/// The longest ring time the loop waits for, s.
const MAX_RING_SECONDS: f32 = 10.0;

/// The bias's integral time, in the tracker's time constants: slower than the tracker, so
/// that the drive's estimate leads the bias that moves it.
const INTEGRAL_TIME_CONSTANTS: f32 = 1.5;

/// The model's slope is solved again after this many of the tracker's time constants.
const SLOPE_TIME_CONSTANTS: f32 = 10.0;

impl Controller {
    /// The tracked drive's last measurement (natural frequency, Q, amplitude), if any.
    pub fn tracked(&self) -> Option<Lock> {
        self.tracking.tracker.and_then(|t| t.lock())
    }

    /// The tracked drive at tick `k` (the AC's phase then `phase`): a solve's slope taken,
    /// the sample fed to the tracker, and at a cycle's end the drive moved in phase and the
    /// bias moved by the integral law.
    pub(super) fn track(&mut self, k: u32, ring: Ring, phase: u32) -> Result<Option<Event>, Fault> {
        if self.trim.result.is_some() {
            let taken = self.take_slope(k);
            // The result dropped with the job (read in place: a device is large).
            self.trim.drop_job();
            return taken;
        }
        let Ring::Stretch(stretch) = ring else {
            return Ok(None);
        };
        // The settings read where they are used, not the whole copied (the tick's budget).
        let tick_hz = self.settings.tick_hz;
        let track_seconds = || self.settings.track_seconds.unwrap_or(1.0);
        let step = self.plan.ac_phase_step;
        if self.tracking.tracker.is_none() {
            // The drive's first sample: the estimate settles from here.
            self.tracking.steady_from = k;
        }
        // The sample is the state at the tick's start; the last command held over the tick
        // before, centred half a tick back: the drive's phase at the sample is half a step
        // behind this tick's, and the amplifier's output behind that.
        let phase = phase
            .wrapping_sub(step / 2)
            .wrapping_sub(self.plan.ac_lag_phase);
        // The drive's frequency as the plan runs it.
        let drive_hz = || tick_hz * (step as f32 / 4_294_967_296.0);
        let tracker = self
            .tracking
            .tracker
            .get_or_insert_with(|| Tracker::new(drive_hz(), stretch));
        // Besides the sample's sum, one small thing a tick (the budget): set a cycle aside
        // and solve its least squares; work out the fit's inputs; fit it. The fit's result
        // is applied on the tick after.
        if tracker.observe(phase, stretch) {
            tracker.solve();
            self.tracking.fit_inputs = None;
            return Ok(None);
        }
        if tracker.pending() {
            match self.tracking.fit_inputs {
                Some((force, gain)) => self.tracking.to_apply = tracker.fit(force, gain),
                None => {
                    let device = self.estimate().unwrap_or(&self.flashed);
                    // The force of the AC at the amplifier's output.
                    let (bias, ac) = (self.plan.bias_volts, self.plan.ac_volts * self.plan.ac_gain);
                    let force = drive_force_per_stretch(device, bias, ac);
                    let gain = (1.0 / (drive_hz() * track_seconds())).min(1.0);
                    self.tracking.fit_inputs = Some((force, gain));
                }
            }
            return Ok(None);
        }
        let Some(lock) = self.tracking.to_apply.take() else {
            return Ok(None);
        };
        let hz = tracker.drive_hz();
        let (target_hz, track_seconds) = (self.settings.target_hz, track_seconds());
        if !((hz - target_hz).abs() <= MAX_DETUNING * target_hz) {
            return Err(Fault::TrackLost {
                drive_hz: hz,
                target_hz,
            });
        }
        // The drive follows, in phase: from this tick at the new frequency. (Fields set in
        // place, not a new plan: the tick's budget.)
        let phase = self.plan.phase(k);
        self.plan.ac_tick = Some(k);
        self.plan.ac_phase_start = phase;
        // In f32 (the tick's budget; f64 is software on the M4F): 2⁻²⁴ of the frequency.
        self.plan.ac_phase_step = (hz / tick_hz * 4_294_967_296.0) as u32;
        // The loop's time: the tracker's constant, or the plant's own ring time Q/(π·f) if
        // longer (none measured: the longest). A loop faster than the ring chases the beat of
        // the ring against the drive: the bias swung wider each time above Q ≈ 100 at 0.2 s.
        let ring_seconds = lock.quality_factor / (core::f32::consts::PI * hz);
        let loop_seconds = if ring_seconds.is_nan() {
            MAX_RING_SECONDS
        } else {
            ring_seconds.clamp(track_seconds, MAX_RING_SECONDS.max(track_seconds))
        };
        let ticks_of = |constants: f32| constants * loop_seconds * tick_hz;
        // A drive still walking to the resonance (the first cycles see the AC's start): the
        // plant has not settled at its frequency, so neither has the estimate (on the
        // reference device at 4.5 kV it read 0.3% high one second in, and the bias moved on
        // it). Once settled, the loop runs on: its integral time is longer than the estimate's.
        let steady = (k - self.tracking.steady_from.min(k)) as f32;
        if steady < ticks_of(SETTLE_TIME_CONSTANTS) {
            let half_width = hz / (2.0 * lock.quality_factor);
            if !((lock.natural_hz - lock.drive_hz).abs() <= SETTLED_HALF_WIDTHS * half_width) {
                self.tracking.steady_from = k;
            }
            return Ok(None);
        }
        // A solve now and then, whatever it gave: one within the trim's tolerance gives no
        // slope (the bias is where it should be) and is not asked again at once.
        let stale = self
            .tracking
            .solved_at
            .is_none_or(|at| k.wrapping_sub(at) as f32 >= ticks_of(SLOPE_TIME_CONSTANTS));
        if stale && self.trim.tracked_hz.is_none() {
            self.trim.want_job(Some((hz, lock.quality_factor)));
            self.tracking.solved_at = Some(k);
        }
        let Some(slope) = self.tracking.volts_squared_per_hz else {
            return Ok(None);
        };
        // The integral law over this cycle (1/hz s long): Φ² moves by slope·error·dt/Ti, the
        // error the cycle's own estimate's (the drive's frequency lags it by the tracker's
        // smoothing).
        // The law integrates from where the output's bias is (the last move's ramp may not
        // be done: from its target instead, the moves would wind up and outrun the slew).
        let integral_seconds = INTEGRAL_TIME_CONSTANTS * loop_seconds;
        let error_hz = target_hz - lock.natural_hz;
        let here = self.plan.ramp_volts(k);
        let squared = here * here + slope * error_hz / (hz * integral_seconds);
        let next_bias_volts = sqrt_f32(squared.max(0.0));
        let ac = self.plan.swing_volts();
        if !(next_bias_volts + ac <= self.max_volts) {
            // The plant needs more than the cap: hold the bias, the drive off, and say so.
            return Ok(Some(self.hold(k, next_bias_volts + ac)));
        }
        // The amplifier must give the new peak, as for a trim's new bias.
        self.amplifier
            .code(next_bias_volts + ac)
            .map_err(Fault::Amplifier)?;
        // From this tick's bias, at the slew rate (this tick's voltage is sent).
        let before = (
            self.plan.start_tick,
            self.plan.start_volts,
            self.plan.bias_volts,
        );
        self.plan.start_tick = k;
        self.plan.start_volts = here;
        self.plan.bias_volts = next_bias_volts;
        if let Err(fault) = self.plan.check_range(next_bias_volts, self.max_volts) {
            (
                self.plan.start_tick,
                self.plan.start_volts,
                self.plan.bias_volts,
            ) = before;
            return Err(fault);
        }
        Ok(None)
    }

    /// A solve's result under a tracked drive: the model's slope dΦ²/df between the bias
    /// and the bias it gives for the target, and the estimate's cap; or a fault.
    fn take_slope(&mut self, k: u32) -> Result<Option<Event>, Fault> {
        let bias = self.plan.bias_volts;
        let Some(result) = self.checked_result()? else {
            return Ok(None);
        };
        match *result {
            TrimResult::Converged { shear_modulus, .. } => {
                self.trim.params.shear_modulus = shear_modulus;
                Ok(None)
            }
            TrimResult::Retune {
                measured_hz,
                shear_modulus,
                bias_volts,
                max_volts,
                predicted,
                ..
            } => {
                self.trim.params.shear_modulus = shear_modulus;
                if predicted.is_some() {
                    self.watch.predict(predicted);
                }
                // A drift's solves are not counted against `MAX_TRIMS` (a lost lock is
                // `TrackLost`), take no secant (`TrimJob::solve`) and leave no point for a
                // later trim's: two points apart in time differ by the drift too.
                self.trim.previous = None;
                let slope = (bias_volts * bias_volts - bias * bias)
                    / (self.settings.target_hz - measured_hz);
                if slope.is_finite() && slope != 0.0 {
                    self.tracking.volts_squared_per_hz = Some(slope);
                }
                self.take_estimate();
                Ok(self.lower_estimate_cap(k, max_volts))
            }
            TrimResult::AboveCeiling(ceiling) => Ok(Some(self.hold_below_ceiling(k, ceiling))),
            TrimResult::Failed(fault) => Err(fault),
        }
    }
}
