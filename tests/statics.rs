//! Statics and small oscillation (model.md §5) against closed forms and a second method.

mod common;

use common::*;
use de_resonator::{Device, DeviceParams, Tuner, REFERENCE_DEVICE};
use std::f64::consts::TAU;

fn devices() -> Vec<DeviceParams<f64>> {
    vec![
        REFERENCE_DEVICE,
        neo_hookean_reference(),
        DeviceParams {
            prestretch_1: 3.0,
            prestretch_2: 1.5,
            length_active: 0.03,
            length_passive: 0.01,
            bar_mass: 0.0,
            jlim: Some(40.0),
            ..REFERENCE_DEVICE
        },
        non_monotone_device(),
    ]
}

/// Neo-Hookean at Φ = 0: s1' = μ(1 + 3λ1p⁻⁴λ2p⁻²) in both membranes, so
/// ω² = μ·L2·H·(1 + 3λ1p⁻⁴λ2p⁻²)·(1 + L1A/L1B)/M.
#[test]
fn neo_hookean_zero_bias_frequency_in_closed_form() {
    for (l1p, l2p, la, lb, m) in [
        (2.0, 2.0, 0.02, 0.02, 2e-3),
        (3.0, 1.2, 0.01, 0.03, 0.0),
        (1.1, 4.0, 0.05, 0.005, 1e-2),
    ] {
        let p = DeviceParams {
            prestretch_1: l1p,
            prestretch_2: l2p,
            length_active: la,
            length_passive: lb,
            bar_mass: m,
            ..neo_hookean_reference()
        };
        let mass = m * la + p.density * p.width * p.thickness * la * (la + lb) / 3.0;
        let omega2 = p.shear_modulus
            * p.width
            * p.thickness
            * (1.0 + 3.0 / (l1p.powi(4) * l2p * l2p))
            * (1.0 + la / lb)
            / mass;
        let f = Device::new(p).unwrap().natural_frequency_hz(l1p);
        assert!(rel(f, omega2.sqrt() / TAU) < 1e-13, "{f}");
    }
}

/// Along the branch ω² = (L2·ε·λ·λ2p²/(M·H))·d(Φ²)/dλ; checked by central differences of
/// Φ(λ), from zero bias to past the limit.
#[test]
fn omega_squared_is_the_slope_of_bias_squared() {
    for p in devices() {
        let d = Device::new(p).unwrap();
        let limit = Tuner::new(d).limit().at.stretch;
        let scale = p.width * permittivity(&p) * p.prestretch_2.powi(2)
            / (effective_mass(&p) * p.thickness);
        for k in 1..=20 {
            let l = p.prestretch_1 + (limit - p.prestretch_1) * f64::from(k) / 18.0;
            let h = 1e-6 * l;
            let slope = (d.bias_volts(l + h).powi(2) - d.bias_volts(l - h).powi(2)) / (2.0 * h);
            let expected = scale * l * slope;
            let w2 = d.omega_squared(l);
            assert!(
                (w2 - expected).abs() < 1e-7 * d.omega_squared(p.prestretch_1),
                "λ = {l}: ω² {w2}, from dΦ²/dλ {expected}"
            );
        }
    }
}

/// With ω² ∝ dΦ²/dλ, ω² = 0 exactly where Φ(λ) folds. While B is taut there is no fold:
/// λ·λ2p²·dΦ̄²/dλ = [s̄1'(λ) − s̄1(λ)/λ] + r·s̄1'(λB) + s̄1(λB)/λ, every term positive for
/// Gent. So Φ rises and ω² > 0 from zero bias to B's slack point λB = λ2p^(−1/2) (or the
/// stretch limit), and device instability never comes first on the static branch.
#[test]
fn no_fold_while_b_is_taut() {
    for p in devices() {
        let d = Device::new(p).unwrap();
        let start = p.prestretch_1;
        let slack_b = p.prestretch_2.powf(-0.5);
        let end = start + (start - slack_b) * p.length_passive / p.length_active;
        let mut previous = 0.0;
        for k in 1..=4000 {
            let l = start + (end - start) * f64::from(k) / 4000.0;
            let below_lock_up = p.jlim.is_none_or(|j| {
                first_invariant(l, p.prestretch_2)
                    .max(first_invariant(passive_stretch(&p, l), p.prestretch_2))
                    < j
            });
            if !below_lock_up {
                break;
            }
            let phi2 = bias_squared(&p, l);
            assert!(phi2 > previous, "Φ² falls at λ = {l} for {p:?}");
            assert!(d.omega_squared(l) > 0.0);
            previous = phi2;
        }
    }
}

/// A second method: Φ(λ) puts the plain-SI force of model.md §4 at rest, and ω² from the
/// core matches −∂λ''/∂λ by finite differences of that force.
#[test]
fn equilibrium_and_frequency_match_the_force_law() {
    for p in devices() {
        let d = Device::new(p).unwrap();
        let limit = Tuner::new(d).limit().at.stretch;
        for k in 0..=10 {
            let l = p.prestretch_1 + (limit - p.prestretch_1) * f64::from(k) / 10.0;
            let volts = d.bias_volts(l);
            assert!((volts * volts - bias_squared(&p, l)).abs() <= 1e-12 * volts * volts);
            let residual = acceleration(&p, l, volts);
            let scale = p.width * p.thickness * p.shear_modulus / effective_mass(&p);
            assert!(
                residual.abs() < 1e-12 * scale,
                "force {residual} at λ = {l}"
            );
            assert!(rel(d.omega_squared(l), omega_squared_fd(&p, l, volts)) < 1e-7);
        }
    }
}

#[test]
fn stretch_for_bias_inverts_bias_volts() {
    for p in devices() {
        let d = Device::new(p).unwrap();
        let limit = Tuner::new(d).limit().at;
        // The limit's volts are those of its offset δ, which is finer than its stretch (the
        // stretch is rounded toward λ1p): the stretch form reaches Φ(limit.stretch).
        let top = d.bias_volts(limit.stretch);
        assert!(top <= limit.volts && top >= limit.volts * (1.0 - 1e-12));
        for k in 0..=10 {
            let volts = top * f64::from(k) / 10.0;
            let l = d.stretch_for_bias(volts, limit.stretch).unwrap();
            assert!((d.bias_volts(l) - volts).abs() <= 1e-9 * limit.volts);
            assert!(d.bias_volts(l) <= volts);
            // Sign of the voltage does not matter.
            assert_eq!(d.stretch_for_bias(-volts, limit.stretch), Some(l));
            // The offset form reaches the limit's own volts.
            let volts = limit.volts * f64::from(k) / 10.0;
            let offset = d.offset_for_bias(volts, limit.offset).unwrap();
            assert!((d.bias_volts_at(offset) - volts).abs() <= 1e-9 * limit.volts);
            assert!(d.bias_volts_at(offset) <= volts && offset <= limit.offset);
        }
        assert_eq!(d.stretch_for_bias(limit.volts * 1.01, limit.stretch), None);
        assert_eq!(d.offset_for_bias(limit.volts * 1.01, limit.offset), None);
        assert_eq!(d.stretch_for_bias(f64::NAN, limit.stretch), None);
        assert_eq!(d.stretch_for_bias(f64::INFINITY, limit.stretch), None);
    }
}

/// The offset for a bias (the core's `root`) against bisection on the same comparison
/// (`bisect`, one evaluation a bit), on random valid devices in f64 and in f32 as flashed:
/// the bias there is below the target, and the two offsets' biases agree to rounding (where Φ's rounding flips the comparison more than once about the
/// root, the two may end on different flips; they are the same floats where it does not).
#[test]
fn offset_for_bias_agrees_with_bisection_on_random_devices() {
    use de_resonator::numerics::real::Real;
    use de_resonator::numerics::roots::bisect;
    /// (the same floats, the biases' difference over the target).
    fn against_bisection<T: Real>(d: &Device<T>, fraction: f64) -> (bool, f64) {
        let max_offset = Tuner::new(*d).limit().at.offset;
        let volts = d.bias_volts_at(max_offset) * T::of(fraction);
        let ours = d
            .offset_for_bias(volts, max_offset)
            .expect("below the limit");
        let (theirs, _) = bisect(T::zero(), max_offset, |x| d.bias_volts_at(x) < volts);
        assert!(d.bias_volts_at(ours) < volts, "{fraction} of the limit");
        let gap = (d.bias_volts_at(ours) - d.bias_volts_at(theirs)).abs() / volts;
        (ours == theirs, gap.to_f64())
    }
    let mut rng = Rng(0x0ff5_e7b1);
    let (mut cases, mut same64, mut same32) = (0, 0, 0);
    let (mut worst64, mut worst32) = (0.0f64, 0.0f64);
    while cases < 400 {
        let p = random_device(&mut rng);
        let (Ok(d64), Ok(d32)) = (Device::new(p), Device::new(p.cast::<f32>())) else {
            continue;
        };
        cases += 1;
        let fraction = rng.range(1e-3, 1.0);
        let (same, gap) = against_bisection(&d64, fraction);
        (same64, worst64) = (same64 + usize::from(same), worst64.max(gap));
        let (same, gap) = against_bisection(&d32, fraction);
        (same32, worst32) = (same32 + usize::from(same), worst32.max(gap));
    }
    println!("same floats: f64 {same64}/{cases}, f32 {same32}/{cases}; biases' worst relative difference f64 {worst64:.1e}, f32 {worst32:.1e}");
    assert!(worst64 < 1e-12, "f64: {worst64}");
    assert!(worst32 < 1e-6, "f32: {worst32}");
}
