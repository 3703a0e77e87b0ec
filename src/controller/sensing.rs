//! The stretch from the capacitance in the tick (feature `probe`, `crate::estimate::capacitance`): each
//! tick's current and voltage go to the probe's lock-in; each window's estimate, widened by
//! `PROBE_SIGMAS` standard errors, is checked against model.md §6 for the device flashed and
//! the trim's estimate, and, at a steady bias, against the capacitance every device of the
//! table's batch has there (model.md §10), one check a tick (the tick's budget).

use super::fault::Fault;
use super::watch::Inputs;
use super::Controller;
use crate::estimate::capacitance::{ProbeLockIn, SensedStretch};
use crate::model::device::Device;
use crate::table::CapacitanceBands;

/// The probe's error on λ beyond its scatter, as a fraction (the amplifier's lag lets some of
/// the probe's own motion through: −3e-4 of λ with host-sim's 2 kHz amplifier at a 1 kHz
/// tick, `crate::estimate::capacitance`): the batch's check allows it on each side.
pub const PROBE_SYSTEMATIC: f32 = 1e-3;

/// Windows ended since a steady bias began when its estimate is first checked against the
/// batch: the second's lies wholly in the hold (within the default 0.25 s settle before the
/// AC), its mean over the ramp's ring the equilibrium's.
const STEADY_WINDOWS: u8 = 2;

/// The lock-in's memory between ticks.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Sensing {
    lock_in: Option<ProbeLockIn>,
    /// The probe's sign at the last tick (`None`: no probe then).
    last_positive: Option<bool>,
    /// The last window's estimate, the next of its checks (`Check::ORDER`), and the steady
    /// bias it was measured at, if it was.
    checking: Option<(SensedStretch, usize, Option<f32>)>,
    /// The bias held without AC or pulse since some tick, and the windows ended since.
    steady: Option<(f32, u8)>,
    /// The capacitance bands of the table's batch (model.md §10), if it has one.
    pub(super) batch: Option<CapacitanceBands>,
}

/// One check of an estimate: the interval's ends against a device.
#[derive(Clone, Copy)]
enum Check {
    /// A number, inside the stretches a device could have (`Device::plausible_stretch`).
    Plausible,
    /// An end of the widened interval (low: false) inside model.md §6 for the device flashed
    /// (true) or the trim's estimate.
    Limit { high: bool, flashed: bool },
    /// At a steady bias, the widened interval meets the stretches every device of the batch
    /// has there (model.md §10).
    Batch,
}

impl Check {
    const ORDER: [Check; 6] = [
        Check::Plausible,
        Check::Limit {
            high: false,
            flashed: true,
        },
        Check::Limit {
            high: true,
            flashed: true,
        },
        Check::Limit {
            high: false,
            flashed: false,
        },
        Check::Limit {
            high: true,
            flashed: false,
        },
        Check::Batch,
    ];
}

impl Controller {
    /// The last window's stretch from the capacitance, if any.
    pub fn sensed(&self) -> Option<SensedStretch> {
        self.sensing.lock_in.and_then(|l| l.last())
    }

    /// Tick `k`'s measurements to the lock-in (the current over the tick before, under the
    /// last command's probe sign; the voltage now, measured or the last command), and one
    /// check of the last estimate.
    pub(super) fn sense(&mut self, k: u32, inputs: &Inputs) -> Option<Fault> {
        self.settings.probe_volts?;
        if let Some(fault) = self.check_sensed(k) {
            return Some(fault);
        }
        let ramp = self.plan.ramp_volts(k);
        let positive = self.plan.probe_positive(k, ramp);
        // The steady hold only matters to the batch's check: none kept without a batch.
        let steady = match self.sensing.steady {
            Some((volts, windows)) if volts == ramp => (volts, windows),
            _ => (ramp, 0),
        };
        let keep = self.sensing.batch.is_some() && self.held(k, ramp);
        self.sensing.steady = keep.then_some(steady);
        let was = core::mem::replace(&mut self.sensing.last_positive, positive);
        let (Some(amps), Some(now), Some(was)) = (inputs.current_amps, positive, was) else {
            // No probe, or no current: the halves start again with the next edge.
            if let Some(lock_in) = self.sensing.lock_in.as_mut() {
                lock_in.restart();
            }
            return None;
        };
        let s = &self.settings;
        let flashed = &self.flashed;
        let lock_in = self
            .sensing
            .lock_in
            .get_or_insert_with(|| ProbeLockIn::new(flashed, s.probe_hz, s.tick_hz));
        // The leakage's part moves with the probe's sign: out, once the watch measures it.
        lock_in.set_conductance(self.leakage.siemens().unwrap_or(0.0));
        let volts = inputs.amplifier_volts.unwrap_or(self.last_volts);
        let edge = (now != was).then_some(was);
        if let Some(estimate) = lock_in.observe(amps, volts, edge) {
            let steady = self.sensing.steady.as_mut().map(|(volts, windows)| {
                *windows = windows.saturating_add(1);
                (*volts, *windows)
            });
            let at =
                steady.and_then(|(volts, windows)| (windows >= STEADY_WINDOWS).then_some(volts));
            self.sensing.checking = Some((estimate, 0, at));
        }
        None
    }

    /// Whether tick `k` holds the plan's bias (`ramp`, the ramp's voltage there) with no AC
    /// and no pulse on it: the probe alone rides on it.
    fn held(&self, k: u32, ramp: f32) -> bool {
        let plan = &self.plan;
        let (from, to) = plan.pulse_ticks;
        ramp == plan.bias_volts
            && (plan.ac_volts == 0.0 || plan.ac_tick.is_none_or(|t| k < t))
            && !(k >= from && k < to)
    }

    /// The next check of the last estimate, if one is due.
    fn check_sensed(&mut self, k: u32) -> Option<Fault> {
        let (estimate, next, steady) = self.sensing.checking?;
        let check = Check::ORDER.get(next).copied();
        self.sensing.checking = check.map(|_| (estimate, next + 1, steady));
        match check? {
            Check::Plausible => {
                let value = estimate.stretch;
                if !(value.is_finite() && estimate.sigma.is_finite()) {
                    let value = if value.is_finite() {
                        estimate.sigma
                    } else {
                        value
                    };
                    return Some(Fault::Sensor { value });
                }
                let (low, high) = self.flashed.plausible_stretch();
                let (from, to) = estimate.widened();
                let outside = [from, to].into_iter().find(|x| !(*x > low && *x < high));
                outside.map(|value| Fault::SensorImplausible { value, low, high })
            }
            Check::Limit { high, flashed } => {
                let device: &Device<f32> = if flashed {
                    &self.flashed
                } else {
                    self.estimate()?
                };
                let (from, to) = estimate.widened();
                let stretch = if high { to } else { from };
                let p = estimate.volts / device.volts_per_unit();
                let mode = device.first_failure(stretch, p * p)?;
                Some(Fault::Limit { mode, tick: k })
            }
            Check::Batch => {
                let volts = steady?;
                // Between the bias held and the voltage the window measured at its blocks'
                // ends (the bias ± the probe; an amplifier a little off its command moves the
                // membrane with it): the hull of both. A ring left in the hold widens σ
                // (the blocks' scatter, ∝ its amplitude) far more than it moves the mean of
                // λ² (∝ its square).
                let bands = self.sensing.batch?;
                let (low_farads, _) = bands.farads_at(volts.min(estimate.volts))?;
                let (_, high_farads) = bands.farads_at(volts.max(estimate.volts))?;
                // The band as the lock-in reads C: through the flashed device's C1.
                let per_stretch_squared = self.flashed.params().farads_per_stretch_squared();
                let low = libm::sqrtf(low_farads / per_stretch_squared);
                let high = libm::sqrtf(high_farads / per_stretch_squared);
                let (from, to) = estimate.widened();
                let meets =
                    to * (1.0 + PROBE_SYSTEMATIC) >= low && from * (1.0 - PROBE_SYSTEMATIC) <= high;
                (!meets).then_some(Fault::OutsideBatch {
                    stretch: estimate.stretch,
                    sigma: estimate.sigma,
                    low,
                    high,
                    volts,
                })
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)] // a test fails by panicking
mod tests {
    extern crate std;
    use std::vec;

    use super::*;
    use crate::controller::Settings;
    use crate::drive::Amplifier;
    use crate::model::device::REFERENCE_DEVICE;
    use crate::table;
    use crate::tuning::Tuner;

    /// The reference device's controller with the probe on (its table as `host-sim lut`
    /// makes it).
    fn controller() -> Controller {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let top = Tuner::new(device)
            .max_bias(table::table_margin(0.05))
            .unwrap();
        let mut points = vec![(0.0f32, 0.0f32); 64];
        table::fill(&device, &top, &[], &mut points).unwrap();
        let mut bytes = vec![0u8; table::table_bytes(64)];
        table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 0.0, &points).unwrap();
        let settings = Settings {
            probe_volts: Some(20.0),
            ..Settings::for_target(44.0)
        };
        let amplifier = Amplifier::new(2.5, 4000.0).unwrap();
        Controller::start(REFERENCE_DEVICE.cast(), &bytes, amplifier, settings)
            .unwrap()
            .0
    }

    /// The five checks of an estimate at 0 V, one a tick: the first fault.
    fn checked(stretch: f32, sigma: f32) -> Option<Fault> {
        let mut c = controller();
        let estimate = SensedStretch {
            stretch,
            sigma,
            farads: 1e-9,
            volts: 0.0,
        };
        c.sensing.checking = Some((estimate, 0, None));
        (0..6).find_map(|k| c.check_sensed(k))
    }

    /// The batch's check alone (the last of `Check::ORDER`), on bands that read as stretches
    /// 2.0 to 2.2 through the flashed C1 at every bias: an estimate whose widened interval
    /// (4σ, then 0.1%) meets them passes; one that misses them faults with the band's ends
    /// and the bias; none is made away from a steady bias or above the bands' last.
    #[test]
    fn the_batch_check_is_the_widened_estimate_against_the_band() {
        use crate::table::{CapacitanceBand, CapacitanceBands, BATCH_BIASES};
        let c1 = controller().flashed.params().farads_per_stretch_squared();
        let mut bands = CapacitanceBands::default();
        for (j, band) in bands.0.iter_mut().enumerate() {
            *band = CapacitanceBand {
                volts: 500.0 * j as f32,
                low_farads: c1 * 4.0,
                high_farads: c1 * 4.84,
            };
        }
        let batch_check = |stretch: f32, sigma: f32, steady: Option<f32>, volts: f32| {
            let mut c = controller();
            c.sensing.batch = Some(bands);
            let estimate = SensedStretch {
                stretch,
                sigma,
                farads: c1 * stretch * stretch,
                volts,
            };
            c.sensing.checking = Some((estimate, Check::ORDER.len() - 1, steady));
            c.check_sensed(0)
        };
        assert_eq!(batch_check(2.1, 1e-3, Some(1000.0), 1000.0), None);
        // 2.204 − 4·0.001 = 2.2, less 0.1%: meets the band's top.
        assert_eq!(batch_check(2.204, 1e-3, Some(1000.0), 1000.0), None);
        assert_eq!(batch_check(1.8, 0.05, Some(1000.0), 1000.0), None);
        match batch_check(2.3, 0.01, Some(1000.0), 1000.0) {
            Some(Fault::OutsideBatch {
                stretch,
                low,
                high,
                volts,
                ..
            }) => {
                assert_eq!((stretch, volts), (2.3, 1000.0));
                assert!(
                    (low - 2.0).abs() < 1e-6 && (high - 2.2).abs() < 1e-6,
                    "{low} {high}"
                );
            }
            other => panic!("{other:?}"),
        }
        match batch_check(1.9, 1e-3, Some(1000.0), 1000.0) {
            Some(Fault::OutsideBatch { .. }) => {}
            other => panic!("{other:?}"),
        }
        assert_eq!(batch_check(2.3, 0.01, None, 1000.0), None);
        let above = 500.0 * BATCH_BIASES as f32;
        assert_eq!(batch_check(2.3, 0.01, Some(above), above), None);
    }

    /// An estimate that is not a number, or whose standard error is not, is a sensor fault
    /// naming the value; one outside the stretches any device could have (its ends included,
    /// σ 0) is implausible; the pre-stretch at 0 V passes.
    #[test]
    fn an_estimate_is_checked_for_numbers_and_plausibility() {
        let (low, high) = controller().flashed.plausible_stretch();
        let prestretch = REFERENCE_DEVICE.prestretch_1 as f32;
        assert_eq!(checked(prestretch, 1e-4), None);
        assert!(matches!(checked(f32::NAN, 1e-4), Some(Fault::Sensor { value }) if value.is_nan()));
        assert!(
            matches!(checked(prestretch, f32::NAN), Some(Fault::Sensor { value }) if value.is_nan())
        );
        assert!(matches!(
            checked(prestretch, f32::INFINITY),
            Some(Fault::Sensor { .. })
        ));
        for at in [low, high] {
            assert!(
                matches!(checked(at, 0.0), Some(Fault::SensorImplausible { value, .. }) if value == at),
                "{at}"
            );
        }
    }
}
