//! Closed-loop trim: the ring's frequency from sensor samples, and μ from a frequency.

mod common;

use de_resonator::estimate::ring::{
    estimate_shear_modulus, high_passed, ring_frequency_hz, RingFit, MAX_WINDOW, MIN_RESOLUTION,
    TIMING_ERROR_TIMES_RESOLUTION,
};
use de_resonator::{Device, DeviceParams, TrimError, REFERENCE_DEVICE};

/// A damped ring with drift and a little noise, sampled at 1 kHz: its frequency back within
/// 1e-4 (the crossings of a damped sine are evenly spaced at its frequency).
#[test]
fn ring_frequency_of_a_damped_drifting_sine() {
    for hz in [28.3f32, 44.0, 61.7] {
        let mut seed = 12345u32;
        let samples: Vec<f32> = (0..500)
            .map(|k| {
                let t = k as f32 / 1000.0;
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let noise = (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
                2.2 + 2e-4 * t
                    + 3e-3 * (-t / 1.5).exp() * (std::f32::consts::TAU * hz * t + 0.3).sin()
                    + 2e-6 * noise
            })
            .collect();
        let f = ring_frequency_hz(samples.iter().copied(), 1000.0, 0.0, 0.0)
            .unwrap()
            .hz;
        assert!((f - hz).abs() < 1e-4 * hz, "{f} for {hz}");
    }
}

/// No ring, no frequency: a flat or missing signal is an error, never a number.
#[test]
fn no_ring_is_an_error() {
    let flat = [2.2f32; 300];
    assert!(matches!(
        ring_frequency_hz(flat.iter().copied(), 1000.0, 0.0, 0.0),
        Err(TrimError::NoRing { .. })
    ));
    let missing = [f32::NAN; MAX_WINDOW];
    assert!(matches!(
        ring_frequency_hz(missing.iter().copied(), 1000.0, 0.0, 0.0),
        Err(TrimError::NoRing { crossings: 0 })
    ));
}

/// μ from a frequency: a device with μ scaled by 0.8 or 1.2 has some f at a bias (the core's
/// statics); from the nominal μ the estimate finds the scaled one again.
#[test]
fn shear_modulus_is_recovered_from_the_frequency() {
    let nominal: DeviceParams<f32> = REFERENCE_DEVICE.cast();
    for (scale, volts) in [
        (0.8f32, 3000.0f32),
        (1.2, 3000.0),
        (1.2, 9000.0),
        (0.8, 7000.0),
    ] {
        let plant = DeviceParams {
            shear_modulus: nominal.shear_modulus * scale,
            ..nominal
        };
        let d = Device::new(plant).unwrap();
        let l = d.stretch_for_bias(volts, d.scan_end_stretch()).unwrap();
        let f = d.natural_frequency_hz(l);
        let mu = estimate_shear_modulus(&nominal, volts, f).unwrap();
        assert!(
            (mu / plant.shear_modulus - 1.0).abs() < 2e-4,
            "{scale} at {volts} V: {mu}"
        );
    }
    // A soft μ finds a far equilibrium past its limit, stiffened by lock-up (41 Hz at μ/4
    // here, where μ gives 32.5): the search must not take it. The wide-range device of
    // scenes/mismatch-stiff.toml, at its trimmed bias.
    let wide = DeviceParams {
        jlim: Some(120.0),
        prestretch_1: 1.5,
        prestretch_2: 3.0,
        length_passive: 0.06,
        ..nominal
    };
    let truth = DeviceParams {
        shear_modulus: 54e3,
        ..wide
    };
    let d = Device::new(truth).unwrap();
    let f = d.natural_frequency_hz(d.stretch_for_bias(7957.8, 3.0).unwrap());
    let mu = estimate_shear_modulus(&wide, 7957.8, f).unwrap();
    assert!((mu / 54e3 - 1.0).abs() < 2e-4, "{mu}");
    assert!(matches!(
        estimate_shear_modulus(&nominal, 3000.0, f32::NAN),
        Err(TrimError::NoEstimate { .. })
    ));
    assert!(matches!(
        estimate_shear_modulus(&nominal, 3000.0, 1000.0),
        Err(TrimError::NoEstimate { .. })
    ));
}

/// A window of the charge as the controller records it without a sensor: the running sum of
/// a current that is white noise of `sigma` (A, a tick) plus a ring whose charge swings
/// ±`amplitude` (A·ticks) at `hz`, 500 ticks at 1 kHz.
fn charge_window(hz: f64, amplitude: f64, sigma: f64, seed: u64) -> Vec<f32> {
    let mut rng = common::Rng(seed);
    let mut walk = 0.0;
    (0..500)
        .map(|k| {
            walk += sigma * rng.gaussian();
            let phase = std::f64::consts::TAU * hz * k as f64 / 1000.0 + 0.4;
            (walk + amplitude * phase.sin()) as f32
        })
        .collect()
}

/// The charge's ring and noise from the window alone: the noise within 10% of the current's,
/// the ring's amplitude within 10% of the one put in, and the resolution falling as the noise
/// rises (ten times the noise, a tenth of it). The frequency, through the high-pass, within
/// three times the timing error the resolution claims (`TIMING_ERROR_TIMES_RESOLUTION`).
#[test]
fn the_charge_window_tells_its_ring_and_noise() {
    for (hz, seed) in [
        (29.5f64, 0x9e37_79b9_7f4a_7c15),
        (44.0, 0xbf58_476d_1ce4_e5b9),
        (61.7, 0x94d0_49bb_1331_11eb),
    ] {
        let half = (0.5 * 1000.0 / hz).round() as usize;
        let quiet = charge_window(hz, 2e-5, 3e-7, seed);
        let ring = RingFit::of(&quiet, half, 0.0);
        assert!((ring.noise / 3e-7 - 1.0).abs() < 0.1, "{hz}: {ring:?}");
        assert!((ring.amplitude / 2e-5 - 1.0).abs() < 0.1, "{hz}: {ring:?}");
        let noisy = RingFit::of(&charge_window(hz, 2e-5, 3e-6, seed), half, 0.0);
        let ratio = noisy.resolution / ring.resolution;
        assert!((ratio / 0.1 - 1.0).abs() < 0.2, "{hz}: {ratio}");
        let f = ring_frequency_hz(high_passed(&quiet, half), 1000.0, 0.0, 0.0)
            .unwrap()
            .hz;
        let claimed = TIMING_ERROR_TIMES_RESOLUTION / ring.resolution;
        assert!(
            (f / hz as f32 - 1.0).abs() < 3.0 * claimed,
            "{f} for {hz}: {claimed:e} claimed"
        );
    }
}

/// A stretch window's running sum, as the trim times it: white noise of `sigma` a sample on
/// a ring of `amplitude` at `hz` (500 samples at 1 kHz, phase `phase`) over a creeping level.
fn stretch_sum(hz: f64, amplitude: f64, sigma: f64, phase: f64, rng: &mut common::Rng) -> Vec<f32> {
    let mut sum = 0.0;
    (0..500)
        .map(|k| {
            let t = k as f64 / 1000.0;
            let ring = amplitude * (std::f64::consts::TAU * hz * t + phase).sin();
            sum += 3e-3 * t + ring + sigma * rng.gaussian();
            sum as f32
        })
        .collect()
}

/// The one resolution rule on the stretch: over 300 windows of its running sum, at three
/// frequencies and noise a twentieth and a seventh of the ring (resolutions 60 to 500: the
/// trim times none below `MIN_RESOLUTION`), the fit finds the sensor's
/// noise within 20% (a window's own scatter) and the ring's amplitude in the sum (a·P/(2π))
/// within 20% where the noise leaves it resolvable; the frequency's relative error times the
/// resolution has the RMS `TIMING_ERROR_TIMES_RESOLUTION` claims (within 0.6–1.5 of it,
/// against the frequency put in), as for the charge; a floor above the noise is the noise
/// the fit takes.
#[test]
fn the_stretch_is_held_to_the_same_resolution() {
    let mut rng = common::Rng(0x2545_f491_4f6c_dd1d);
    let (mut sum, mut n) = (0.0f64, 0.0f64);
    for hz in [29.5f64, 44.0, 61.7] {
        let half = (0.5 * 1000.0 / hz).round() as usize;
        let in_sum = 1e-3 * 1000.0 / (std::f64::consts::TAU * hz);
        for sigma in [5e-5, 1.5e-4] {
            for _ in 0..50 {
                let phase = rng.range(0.0, std::f64::consts::TAU);
                let window = stretch_sum(hz, 1e-3, sigma, phase, &mut rng);
                let fit = RingFit::of(&window, half, 0.0);
                assert!(
                    (f64::from(fit.noise) / sigma - 1.0).abs() < 0.2,
                    "{hz}: {fit:?}"
                );
                assert!(
                    (f64::from(fit.amplitude) / in_sum - 1.0).abs() < 0.2,
                    "{hz}: {fit:?}"
                );
                assert!(fit.resolution >= MIN_RESOLUTION, "{hz}: {fit:?}");
                let f = ring_frequency_hz(
                    high_passed(&window, half),
                    1000.0,
                    fit.band(half),
                    half as f32,
                )
                .unwrap()
                .hz;
                let error = f64::from(f) / hz - 1.0;
                sum += (error * f64::from(fit.resolution)).powi(2);
                n += 1.0;
                let floored = RingFit::of(&window, half, 1e-2);
                assert_eq!(floored.noise, 1e-2);
            }
        }
    }
    let rms = (sum / n).sqrt() / f64::from(TIMING_ERROR_TIMES_RESOLUTION);
    eprintln!("stretch: RMS of error x resolution {rms} of the claim");
    assert!(
        (0.6..1.5).contains(&rms),
        "{rms} of the claimed timing error"
    );
}

/// A stretch window's running sum of a free ring of `amplitude` at `hz` decaying to quality
/// factor `quality` (model.md §7: e^(−π·f·t/Q)), white noise of `sigma` a sample, 500 samples
/// at 1 kHz.
fn decaying_sum(
    (hz, quality): (f64, f64),
    amplitude: f64,
    sigma: f64,
    rng: &mut common::Rng,
) -> Vec<f32> {
    let phase = rng.range(0.0, std::f64::consts::TAU);
    let mut sum = 0.0;
    (0..500)
        .map(|k| {
            let t = k as f64 / 1000.0;
            let decay = (-std::f64::consts::PI * hz * t / quality).exp();
            sum += amplitude * decay * (std::f64::consts::TAU * hz * t + phase).sin()
                + sigma * rng.gaussian();
            sum as f32
        })
        .collect()
}

/// Q from a window's decay: over 100 windows each of rings of Q 30 to 1,000 at three
/// frequencies and two noises (a twentieth and a seventh of the ring), the Q put in is at or
/// below the window's highest (`RingQuality::high`) in all but 1% (three deviations: 0.13%
/// expected), and the median estimate within 5% of it where the decay over the window is
/// more than its error (Q ≤ 200), the median highest under twice it at the lower noise;
/// an undamped ring's highest Q is above 1,000 in 99%. The deviation the highest claims
/// (a third of the log ratio's way to it) covers the estimates' scatter about the Q put in:
/// their ratio's RMS between 0.3 and 1.2.
#[test]
fn the_ring_tells_its_quality_factor_within_its_error() {
    use de_resonator::estimate::ring::{RingQuality, QUALITY_DEVIATIONS};
    let mut rng = common::Rng(0x853c_49e6_748f_ea9b);
    for hz in [29.5f64, 44.0, 61.7] {
        let half = (0.5 * 1000.0 / hz).round() as usize;
        for sigma in [5e-5, 1.5e-4] {
            for quality in [30.0, 100.0, 200.0, 1000.0, f64::INFINITY] {
                let (mut above, mut estimates, mut highs) = (0, Vec::new(), Vec::new());
                let mut z = Vec::new();
                for _ in 0..100 {
                    let window = decaying_sum((hz, quality), 1e-3, sigma, &mut rng);
                    let q = RingQuality::of(&window, half, 0.0, 1000.0, hz as f32);
                    assert!(q.high >= q.quality_factor || q.high.is_infinite(), "{q:?}");
                    if f64::from(q.high) < quality.min(1000.0) {
                        above += 1;
                    }
                    estimates.push(q.quality_factor);
                    highs.push(q.high);
                    // The halves' log ratio, π·f·T/Q (T a half's 0.25 s), against the one put
                    // in, over the deviation `high` claims for it (a third of the way down).
                    let log_ratio = |q: f64| std::f64::consts::PI * hz * 0.25 / q;
                    let claimed = (log_ratio(f64::from(q.quality_factor))
                        - log_ratio(f64::from(q.high)))
                        / f64::from(QUALITY_DEVIATIONS);
                    if claimed > 0.0 && q.high.is_finite() {
                        let off = log_ratio(f64::from(q.quality_factor)) - log_ratio(quality);
                        z.push(off / claimed);
                    }
                }
                // The deviation claimed is at least the scatter's, and not far above it
                // (an error a period correlated: about twice the scatter of these white
                // rings), where the decay is told (Q ≤ 200, the quieter: a finite highest).
                let rms = (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
                assert!(
                    quality > 200.0 || sigma > 5e-5 || (z.len() >= 90 && (0.3..1.2).contains(&rms)),
                    "{hz} Hz, σ {sigma}, Q {quality}: {} claims, RMS {rms}",
                    z.len()
                );
                assert!(above <= 1, "{hz} Hz, σ {sigma}, Q {quality}: {above} above");
                if quality <= 200.0 {
                    estimates.sort_by(f32::total_cmp);
                    let median = f64::from(estimates[50]);
                    assert!(
                        (median / quality - 1.0).abs() < 0.05,
                        "{hz} Hz, σ {sigma}, Q {quality}: median {median}"
                    );
                    // And not wider than the scatter needs, the quieter ring's.
                    highs.sort_by(f32::total_cmp);
                    let high = f64::from(highs[50]);
                    assert!(
                        sigma > 5e-5 || high < 2.0 * quality,
                        "{hz} Hz, σ {sigma}, Q {quality}: median high {high}"
                    );
                }
            }
        }
    }
    // No frequency, or no time: nothing bounds Q.
    let window = decaying_sum((44.0, 100.0), 1e-3, 5e-5, &mut rng);
    for (per_second, hz) in [(1000.0, f32::NAN), (0.0, 44.0), (1000.0, -44.0)] {
        let q = RingQuality::of(&window, 11, 0.0, per_second, hz);
        assert!(
            q.quality_factor.is_infinite() && q.high.is_infinite(),
            "{q:?}"
        );
    }
}

/// The halves' amplitudes are fitted, not averaged: a steady ring (no decay, no noise) in a
/// window as short as 60 samples at 1 kHz (each half's fit over 8 high-passed samples, a
/// third of a 44 Hz period, where a sine and a cosine are far from orthogonal) reads the
/// same amplitude in both halves at any phase (Q above 10⁴, or unbounded); a ring of Q 30
/// in 180 samples (each half's fit over three periods; the trim's shortest window, four
/// periods, fits one) its Q within 3% at any phase (its decay over the halves' 90 ms,
/// e^(−π·44·0.09/30)), the highest at or above it.
#[test]
fn a_ring_reads_its_decay_over_part_of_a_period() {
    use de_resonator::estimate::ring::RingQuality;
    let (hz, half) = (44.0f64, 11);
    for quality in [f64::INFINITY, 30.0] {
        for k in 0..16 {
            let phase = k as f64 * std::f64::consts::TAU / 16.0;
            let mut sum = 0.0;
            let len = if quality.is_finite() { 180 } else { 60 };
            let window: Vec<f32> = (0..len)
                .map(|n| {
                    let t = n as f64 / 1000.0;
                    let decay = (-std::f64::consts::PI * hz * t / quality).exp();
                    sum += 1e-3 * decay * (std::f64::consts::TAU * hz * t + phase).sin();
                    sum as f32
                })
                .collect();
            let q = RingQuality::of(&window, half, 0.0, 1000.0, hz as f32);
            let read = f64::from(q.quality_factor);
            let ok = if quality.is_finite() {
                (read / quality - 1.0).abs() < 0.03 && f64::from(q.high) >= quality
            } else {
                read > 1e4
            };
            assert!(ok, "Q {quality}, phase {phase}: {q:?}");
        }
    }
}
