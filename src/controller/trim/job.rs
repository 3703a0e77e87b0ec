//! A trim's work as the tick hands it out ([`TrimJob`]: a copy of everything the solve
//! needs) and its answer ([`TrimDone`], [`TrimResult`]): solved outside the tick, by a
//! low-priority caller, with no access to the controller.

use super::ring::{
    declared, half_samples, outside_batch, pulse_ring, pulse_seconds, ring_tolerance, NextRing,
};
use crate::acquire::InputNoise;
use crate::controller::envelope::Predicted;
use crate::controller::fault::Fault;
use crate::controller::settings::{guarded, Settings, MAX_TRIMS, TRIM_SECANT_STEP};
use crate::estimate::ring::{
    estimate_shear_modulus, high_passed, model_hz, ring_frequency_hz, NoiseFrom, RingFit, RingGain,
    RingInput, RingQuality, TrimError, MAX_WINDOW, TIMING_ERROR_TIMES_RESOLUTION,
};
use crate::model::device::{Device, DeviceParams};
use crate::model::statics::Equilibrium;
use crate::model::swing::{AcDrive, Ramp, Resonance, SwingError};
use crate::tuning::{TuneError, Tuner};

/// A trim's work, handed out by `Controller::trim_job`: solved outside the tick.
#[derive(Clone, Debug)]
pub struct TrimJob {
    pub(super) window: [f32; MAX_WINDOW],
    pub(super) len: usize,
    pub(super) settings: Settings,
    pub(super) params: DeviceParams<f32>,
    pub(super) bias_volts: f32,
    pub(super) tuned: bool,
    pub(super) count: u8,
    pub(super) previous: Option<(f32, f32)>,
    /// The cap in force when the job was made, V: the result never goes above it.
    pub(super) cap_volts: f32,
    /// Whether the window holds the charge (high-passed before its crossings are found).
    pub(super) from_charge: bool,
    /// The noise the image's front end declares for the inputs (the floor of the window's).
    pub(super) inputs: InputNoise,
    /// What the window before showed of the ring (`TrimState::ring`).
    pub(super) ring: NextRing,
    /// Measured by the tracker (the window is not read), Hz, and its Q (NaN: none).
    pub(super) measured_hz: Option<f32>,
    pub(super) quality_factor: f32,
    /// Its number, carried by its result.
    pub(super) job: u32,
    /// The batch's shear modulus range, Pa (model.md §10): an estimate outside it is said
    /// before any retune is solved from it.
    pub(super) batch_modulus: Option<(f32, f32)>,
}

/// What a trim's window told of the ring (`TrimJob::time_window`), or a tracked drive's
/// measurement, which reads no window.
struct Heard {
    measured_hz: f32,
    /// What the timing may be off by, relative, and the resolution that says so.
    timing_error: f32,
    resolution: Option<f32>,
    /// The ring seen against the one the statics gave for this bias, and the share of the
    /// window it was timed over: the plant's damping and the window's settling, which the
    /// next pulse's reckoning then takes in.
    ring_seen: f32,
    ring_span: f32,
    /// The ring the window heard, in its input (the AC a trim pauses rings on in it: what
    /// the drive then starts on).
    heard_ring: Option<(RingInput, f32)>,
    /// Its decay: the plant's Q (model.md §7), whatever the device file says.
    quality: Option<RingQuality>,
}

impl Heard {
    /// A frequency measured, nothing more known of the ring than the last window left (a
    /// tracked drive's, which reads no window; a window's before its ring is weighed).
    fn measured(measured_hz: f32, ring: NextRing) -> Self {
        Heard {
            measured_hz,
            timing_error: 0.0,
            resolution: None,
            ring_seen: ring.seen,
            ring_span: ring.span,
            heard_ring: None,
            quality: None,
        }
    }
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
    /// The estimate needs more than the cap in force: hold.
    AboveCeiling(Ceiling),
    /// No ring, no estimate, no convergence, or no safe bias: a fault.
    Failed(Fault),
}

/// A solve whose estimate needs `needed_volts` (bias and AC) above the lower of the cap in
/// force and its own cap `max_volts` (which the controller takes as `Retune`'s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ceiling {
    pub measured_hz: f32,
    pub shear_modulus: f32,
    pub needed_volts: f32,
    pub max_volts: f32,
}

impl TrimJob {
    /// The job for the window in `state`, measured at `bias_volts`, on inputs that declare
    /// `inputs`.
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
        // Before a tracked drive, the ring's trim need only bring the resonance within the
        // tracker's reach: the tracker holds the target with the drive on.
        let tolerance = match self.measured_hz {
            Some(_) => s.trim_tolerance.unwrap_or(0.0),
            None => ring_tolerance(&s),
        };
        let Heard {
            measured_hz,
            timing_error,
            resolution,
            ring_seen,
            ring_span,
            heard_ring,
            quality,
        } = match self.measured_hz {
            Some(hz) => Heard::measured(hz, self.ring),
            None => self.time_window(tolerance)?,
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
        let bias_volts = self.next_bias(&tuner, measured_hz, (at_cap, max_volts), margin)?;
        // A bias above the estimate's cap is no fault here: the controller takes the lower
        // cap and comes down to it at the slew rate (from where it is, `Plan::start_under`;
        // while tracking, a hold).
        let needed_volts = bias_volts + s.swing_volts();
        if !(needed_volts <= max_volts) {
            return Ok(TrimResult::AboveCeiling(Ceiling {
                measured_hz,
                shear_modulus,
                needed_volts,
                max_volts: estimate_volts,
            }));
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

    /// The ring in the window timed (model.md §7): its frequency, how well it was timed
    /// (refused where the window cannot time it to the trim's `tolerance`), how strong it
    /// rang against the statics' prediction, and its Q.
    fn time_window(&self, tolerance: f32) -> Result<Heard, Fault> {
        let s = self.settings;
        let window = self.window.get(..self.len).unwrap_or(&self.window);
        let (stride, _) = s.trim_window();
        let sample_hz = s.tick_hz / stride as f32;
        let input = if self.from_charge {
            RingInput::Charge
        } else {
            RingInput::Stretch
        };
        // A period of the ring the model expects at the bias (the target's if none): a
        // mismatch of a few percent only scales the ring a little.
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
        // Too weak a ring is said, not estimated from (a window with neither ring nor noise
        // has no ring to time: `NoRing`, below).
        let ring = RingFit::of(window, half, floor);
        let needed = RingFit::needed(tolerance);
        let rang = ring.amplitude > 0.0 || ring.noise > 0.0;
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
        if rang && !(ring.resolution >= needed) {
            return Err(refused(ring.resolution));
        }
        // Timed where the ring stands out of the noise (`ring_frequency_hz`'s band and its
        // check of each half period): a ring that fades into the noise before the window
        // ends is resolved over the share it was timed in.
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
        if rang && !(timed >= needed) {
            return Err(refused(timed));
        }
        let mut heard = Heard::measured(timing.hz, self.ring);
        if timed.is_finite() {
            heard.timing_error = TIMING_ERROR_TIMES_RESOLUTION / timed;
            heard.resolution = Some(timed);
        }
        let predicted = self
            .ring
            .gain
            .ring(input, self.bias_volts, s.trim_pulse_volts);
        let seen = ring.amplitude * to_ring / predicted;
        if seen > 0.0 && seen.is_finite() {
            heard.ring_seen = seen;
        }
        heard.heard_ring = Some((input, ring.amplitude * to_ring));
        heard.quality = Some(RingQuality::of(window, half, floor, sample_hz, timing.hz));
        heard.ring_span = timing.span;
        Ok(heard)
    }

    /// The next bias for the target on the estimate `tuner`, from the bias measured at: the
    /// secant through the last two measurements where it stays within its trust region and
    /// under `max_volts` with the drive's swing, else the estimate's own solve (`at_cap`: its
    /// bias at the cap, which says on which side a target out of its reach lies).
    fn next_bias(
        &self,
        tuner: &Tuner<f32>,
        measured_hz: f32,
        (at_cap, max_volts): (Equilibrium<f32>, f32),
        margin: f32,
    ) -> Result<f32, Fault> {
        let s = &self.settings;
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
        match secant {
            Some(volts) => Ok(volts),
            None => match tuner.tune(s.target_hz, margin) {
                Ok(solved) => Ok(solved.volts),
                // Past the estimate's reach under the margin on the side more bias goes
                // (f falls with the bias on most devices, rises on some: model.md §5): the
                // target needs more than the cap (the bias for it at no margin, at least
                // the limit's), a hold that says so, not a fault.
                Err(TuneError::OutOfRange { .. })
                    if (s.target_hz - at_cap.natural_frequency_hz)
                        * (at_cap.natural_frequency_hz
                            - tuner.zero_bias().natural_frequency_hz)
                        > 0.0 =>
                {
                    Ok(tuner
                        .tune(s.target_hz, 0.0)
                        .map_or(tuner.limit().at.volts, |solved| solved.volts))
                }
                Err(error) => Err(Fault::Tune(error)),
            },
        }
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

#[cfg(test)]
#[allow(clippy::panic)] // a test fails by panicking
mod tests;
