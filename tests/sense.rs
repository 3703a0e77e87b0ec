//! The stretch from the capacitance (`de_resonator::estimate::capacitance`) against a membrane written out
//! here: the charge C(λ)·Φ of a parallel-plate capacitor (model.md §8, paper eq. 1, from the
//! geometry, not the core's formula), the leakage Φ/R, and Gaussian noise on the current.

mod common;

use common::Rng;
use de_resonator::estimate::capacitance::{ProbeLockIn, SensedStretch};
use de_resonator::model::device::Device;
use de_resonator::REFERENCE_DEVICE;

/// C(λ) of the reference device, F: ε0·εr·(L1A·λ)·(L2·λ2p)/(H/(λ·λ2p)) over λ (plate area
/// L1A·λ × L2·λ2p, thickness H/(λ·λ2p) by incompressibility), that is ε·L1A·L2·λ²·λ2p²/H.
fn capacitance(stretch: f64) -> f64 {
    let p = REFERENCE_DEVICE;
    let area = p.length_active * stretch * p.width * p.prestretch_2;
    let thickness = p.thickness / (stretch * p.prestretch_2);
    8.8541878128e-12 * p.relative_permittivity * area / thickness
}

/// A standard normal draw (Box–Muller).
fn gaussian(rng: &mut Rng) -> f64 {
    let (u, v) = (rng.unit().max(1e-300), rng.unit());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// What the lock-in reads over `ticks` at 1 kHz from a membrane at `stretch(t)` under a
/// 3 kV bias ramping 2 V a tick, a 100 V AC at 40 Hz, a ±`probe` V square flipping every
/// `half` ticks, 1 GΩ of leakage, and `noise_amps` rms on the current a tick.
fn read(
    stretch: impl Fn(f64) -> f64,
    probe: f64,
    half: u32,
    noise_amps: f64,
    ticks: u32,
) -> Vec<SensedStretch> {
    let device = Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap();
    let dt = 1e-3;
    let mut lock_in = ProbeLockIn::new(&device, 1.0 / (2.0 * f64::from(half) * dt) as f32, 1000.0);
    lock_in.set_conductance(1e-9);
    let positive = |k: u32| (k / half).is_multiple_of(2);
    let volts = |k: u32| {
        let t = f64::from(k) * dt;
        let sign = if positive(k) { 1.0 } else { -1.0 };
        3000.0
            + 2.0 * f64::from(k)
            + 100.0 * (std::f64::consts::TAU * 40.0 * t).sin()
            + sign * probe
    };
    let mut rng = Rng(0x5eed_cafe);
    let mut out = Vec::new();
    for k in 1..ticks {
        // The command of tick k − 1 held over [t(k−1), t(k)]: the charge's change, the
        // leakage at that voltage, and the noise.
        let (t0, t1) = (f64::from(k - 1) * dt, f64::from(k) * dt);
        let held = volts(k - 1);
        let before = capacitance(stretch(t0)) * if k == 1 { 0.0 } else { volts(k - 2) };
        let after = capacitance(stretch(t1)) * held;
        let amps = (after - before) / dt + held / 1e9 + noise_amps * gaussian(&mut rng);
        let edge = (positive(k) != positive(k - 1)).then_some(positive(k - 1));
        if let Some(s) = lock_in.observe(amps as f32, held as f32, edge) {
            out.push(s);
        }
    }
    out
}

/// A still membrane under bias, ramp, AC, probe and leakage reads its own stretch, to f32's
/// digits, whatever the probe's half period.
#[test]
fn a_still_membrane_reads_its_stretch() {
    for stretch in [1.2, 2.0, 3.5] {
        for half in [1, 2, 5] {
            let read = read(|_| stretch, 20.0, half, 0.0, 2000);
            assert!(read.len() >= 10, "{stretch} {half}: {}", read.len());
            for s in &read {
                let error = f64::from(s.stretch) / stretch - 1.0;
                assert!(error.abs() < 2e-5, "{stretch} {half}: {s:?}");
            }
        }
    }
}

/// A membrane swinging 1% at 40 Hz (the AC's motion, and its Φ·C'·dλ/dt current) reads its
/// mean: the blocks cancel what is smooth across them; the swing left in their scatter
/// widens the estimate, which still holds the mean.
#[test]
fn a_swinging_membrane_reads_its_mean() {
    let mean = 2.0;
    let swing = |t: f64| mean * (1.0 + 0.01 * (std::f64::consts::TAU * 40.0 * t).sin());
    for s in read(swing, 20.0, 1, 0.0, 3000) {
        // C ∝ λ²: the window's mean C is that of λ·(1 + ¼·0.01²) at most.
        let error = f64::from(s.stretch) / mean - 1.0;
        assert!(error.abs() < 1e-3, "{s:?}");
        let (low, high) = s.widened();
        assert!(f64::from(low) < mean && f64::from(high) > mean, "{s:?}");
        assert!(s.sigma > 1e-4, "{s:?}");
    }
}

/// With noise on the current the standard error it reports is the scatter of its estimates,
/// and both are what the lock-in's arithmetic predicts: a block's charge noise √20·σ·T·√n
/// (weights 1, 3, 3, 1 over halves of n ticks) against its probe signal 16·p·C, over B
/// blocks, halved for λ (λ ∝ √C).
#[test]
fn the_standard_error_is_the_noise_the_arithmetic_predicts() {
    let (stretch, probe, noise) = (2.5, 20.0, 1e-6);
    for half in [1u32, 2] {
        let read = read(|_| stretch, probe, half, noise, 60_000);
        let n = read.len() as f64;
        let mean = read.iter().map(|s| f64::from(s.stretch)).sum::<f64>() / n;
        let scatter = (read
            .iter()
            .map(|s| (f64::from(s.stretch) - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0))
            .sqrt();
        let reported = read.iter().map(|s| f64::from(s.sigma)).sum::<f64>() / n;
        let blocks = (0.1 * 1000.0 / (4.0 * f64::from(half))).ceil().max(8.0);
        let c = capacitance(stretch);
        let per_block = 20f64.sqrt() * noise * 1e-3 * f64::from(half).sqrt() / (16.0 * probe * c);
        let predicted = 0.5 * stretch * per_block / blocks.sqrt();
        assert!(
            (reported / predicted - 1.0).abs() < 0.1,
            "n {half}: reported {reported:.3e}, predicted {predicted:.3e}"
        );
        assert!(
            (scatter / predicted - 1.0).abs() < 0.15,
            "n {half}: scatter {scatter:.3e}, predicted {predicted:.3e}"
        );
        assert!((mean / stretch - 1.0).abs() < 3.0 * scatter / n.sqrt() + 1e-6);
    }
}

/// The controller with the probe on (feature `probe`).
#[cfg(feature = "probe")]
mod controller {
    use super::{capacitance, gaussian};
    use crate::common::{made_table, Rng};
    use de_resonator::model::device::Device;
    use de_resonator::{Controller, Event, FailureMode, Fault, Inputs, Settings, REFERENCE_DEVICE};

    /// The reference controller with the probe on, its current from a membrane written out
    /// here at `stretch(bias)` (the ramp's voltage: the membrane does not follow the probe, far
    /// above its resonance): the first fault within `ticks`, if any.
    fn controller_reading(
        stretch: impl Fn(f64) -> f64,
        noise_amps: f64,
        ticks: u32,
    ) -> Option<Fault> {
        let settings = Settings {
            probe_volts: Some(20.0),
            probe_hz: 500.0,
            ..Settings::for_target(44.0)
        };
        let table = made_table(REFERENCE_DEVICE, 0.05, 64);
        let amplifier = crate::common::amplifier();
        let (mut c, _) =
            Controller::start(REFERENCE_DEVICE.cast(), &table, amplifier, settings).unwrap();
        let mut rng = Rng(7);
        let (mut volts, mut bias, mut charge) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..ticks {
            let inputs = if k == 0 {
                Inputs::NONE
            } else {
                let now = capacitance(stretch(bias)) * volts;
                let amps = (now - charge) / 1e-3 + noise_amps * gaussian(&mut rng);
                charge = now;
                Inputs::current(amps as f32)
            };
            let out = c.tick(inputs);
            if let Some(Event::Fault(fault)) = out.event {
                return Some(fault);
            }
            volts = f64::from(out.volts);
            bias = f64::from(c.plan().ramp_volts(k));
        }
        assert!(c.sensed().is_some());
        None
    }

    /// The monitor checks the stretch from C widened by its uncertainty: a membrane at its
    /// equilibrium passes for 3 s; one 1.55 times as stretched (past 3.29, where the passive
    /// membrane goes slack at the biases the ramp reaches: model.md §6.3) is a `Limit` fault;
    /// noise so large that the widened estimate leaves the stretches any device could have is a
    /// fault, never a pass.
    #[test]
    fn the_monitor_checks_the_stretch_from_c_widened() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let (_, high) = device.plausible_stretch();
        let rest = |volts: f64| device.stretch_for_bias(volts, high).unwrap();
        assert_eq!(controller_reading(rest, 1e-6, 3000), None);
        let stretched = |volts: f64| 1.55 * rest(volts);
        let fault = controller_reading(stretched, 1e-6, 3000);
        assert!(
            matches!(
                fault,
                Some(Fault::Limit {
                    mode: FailureMode::LossOfTension1,
                    ..
                })
            ),
            "{fault:?}"
        );
        let noisy = controller_reading(rest, 3e-3, 3000);
        assert!(
            matches!(
                noisy,
                Some(Fault::SensorImplausible { .. } | Fault::Sensor { .. } | Fault::Limit { .. })
            ),
            "{noisy:?}"
        );
    }
}
