//! The six checks of MODEL.md §6 and the limit of the loading branch: each mode's limit
//! meets its own analytic boundary condition, computed here in plain SI.

mod common;

use common::*;
use de_resonator::material::Gent;
use de_resonator::{Device, DeviceParams, FailureMode, Limit, Tuner, REFERENCE_DEVICE};

fn limit_of(p: DeviceParams<f64>) -> Limit<f64> {
    *Tuner::new(Device::new(p).unwrap()).limit()
}

/// The smallest float above `x`.
fn next_up(x: f64) -> f64 {
    f64::from_bits(x.to_bits() + 1)
}

/// A free equi-biaxial neo-Hookean membrane (λ1 = λ2 = λ, no force) is held by
/// Φ̄² = λ⁻² − λ⁻⁸; the Hessian test of §6.2 fails at λ = 2^(1/3) ≈ 1.26, Φ̄ ≈ 0.687
/// (Zhao & Suo 2007).
#[test]
fn free_equibiaxial_membrane_loses_stability_at_the_classic_point() {
    let m = Gent::<f64>::neo_hookean();
    let definite = |l: f64| {
        let phi2 = l.powi(-2) - l.powi(-8);
        m.hessian_under_bias(l, l, phi2).definiteness() > 0.0
    };
    let (mut lo, mut hi) = (1.01, 2.0);
    assert!(definite(lo) && !definite(hi));
    while hi - lo > 1e-14 {
        let mid = 0.5 * (lo + hi);
        if definite(mid) {
            lo = mid
        } else {
            hi = mid
        }
    }
    let exact = 2f64.powf(1.0 / 3.0);
    assert!((lo - exact).abs() < 1e-9, "λ = {lo}");
    let phi = (lo.powi(-2) - lo.powi(-8)).sqrt();
    assert!((phi - 0.687).abs() < 5e-4, "Φ̄ = {phi}");
}

/// The EMI limit of the reference device: the Hessian of F = Ws − ½ε(Φ/H)²λ1²λ2², taken
/// here by finite differences of the plain energy, turns singular there: its determinant
/// changes sign across the limit and is near zero against its value at zero bias.
#[test]
fn emi_limit_is_where_the_free_energy_hessian_turns_singular() {
    let p = REFERENCE_DEVICE;
    let d = Device::new(p).unwrap();
    let limit = limit_of(p);
    assert_eq!(limit.mode, FailureMode::Emi);
    let det = |a: f64| {
        let eps_e2 = permittivity(&p) * (d.bias_volts(a) / p.thickness).powi(2);
        let f = |a: f64, b: f64| energy(&p, a, b) - 0.5 * eps_e2 * a * a * b * b;
        let (b, h) = (p.prestretch_2, 1e-4);
        let faa = (f(a + h, b) - 2.0 * f(a, b) + f(a - h, b)) / (h * h);
        let fbb = (f(a, b + h) - 2.0 * f(a, b) + f(a, b - h)) / (h * h);
        let fab =
            (f(a + h, b + h) - f(a + h, b - h) - f(a - h, b + h) + f(a - h, b - h)) / (4.0 * h * h);
        faa * fbb - fab * fab
    };
    let l = limit.at.stretch;
    let at_zero_bias = det(p.prestretch_1);
    assert!(det(l - 1e-3) > 0.0 && det(l + 1e-3) < 0.0);
    assert!(
        det(l).abs() < 1e-5 * at_zero_bias,
        "{} vs {at_zero_bias}",
        det(l)
    );
}

/// Loss of tension in direction 1 (neo-Hookean): s1(λB, λ2p) = 0 at λB = λ2p^(−1/2).
#[test]
fn loss_of_tension_1_at_the_slack_stretch() {
    let p = DeviceParams {
        prestretch_1: 0.7,
        prestretch_2: 2.8,
        length_active: 0.02,
        length_passive: 0.05,
        jlim: None,
        ..REFERENCE_DEVICE
    };
    let limit = limit_of(p);
    assert_eq!(limit.mode, FailureMode::LossOfTension1);
    let lb = passive_stretch(&p, limit.at.stretch);
    assert!((lb - p.prestretch_2.powf(-0.5)).abs() < 1e-12, "λB = {lb}");
}

/// Breakdown: E = Φ·λ·λ2p/H reaches E_B.
#[test]
fn breakdown_at_the_breakdown_field() {
    let p = DeviceParams {
        breakdown_field: 30e6,
        ..REFERENCE_DEVICE
    };
    let limit = limit_of(p);
    assert_eq!(limit.mode, FailureMode::Breakdown);
    let field = limit.at.volts * limit.at.stretch * p.prestretch_2 / p.thickness;
    assert!(rel(field, p.breakdown_field) < 1e-12, "E = {field}");
}

/// Stretch limit: I1 reaches Jlim in A or B (MODEL.md §6.6 as written: I1 < Jlim).
#[test]
fn stretch_limit_at_jlim() {
    let p = DeviceParams {
        jlim: Some(9.0), // I1 = 8.0625 at the reference pre-stretch
        ..REFERENCE_DEVICE
    };
    let limit = limit_of(p);
    assert_eq!(limit.mode, FailureMode::StretchLimit);
    let l2p = p.prestretch_2;
    let i1 = first_invariant(limit.at.stretch, l2p)
        .max(first_invariant(passive_stretch(&p, limit.at.stretch), l2p));
    assert!(rel(i1, 9.0) < 1e-12, "I1 = {i1}");
}

/// Loss of tension in direction 2 of A: the true stress λ2p·s2 − ε·E² reaches zero.
#[test]
fn loss_of_tension_2a_where_the_true_stress_vanishes() {
    let p = DeviceParams {
        prestretch_1: 3.0,
        prestretch_2: 0.8,
        jlim: None,
        ..REFERENCE_DEVICE
    };
    let limit = limit_of(p);
    assert_eq!(limit.mode, FailureMode::LossOfTension2a);
    let l = limit.at.stretch;
    let field = limit.at.volts * l * p.prestretch_2 / p.thickness;
    let sigma2 = p.prestretch_2 * s2(&p, l, p.prestretch_2) - permittivity(&p) * field * field;
    assert!(sigma2.abs() < 1e-9 * p.shear_modulus, "σ2 = {sigma2} Pa");
}

/// Loss of tension in direction 2 of B (λB·λ2p² < 1 makes s2(λB, λ2p) < 0): A's own
/// direction-2 tension always goes first on the static branch, so the check is exercised
/// at a state off the branch: no bias, B compressed to λB = 1.3 with λ2p = 0.8.
#[test]
fn loss_of_tension_2b_off_the_branch() {
    let p = DeviceParams {
        prestretch_1: 3.0,
        prestretch_2: 0.8,
        jlim: None,
        ..REFERENCE_DEVICE
    };
    let d = Device::new(p).unwrap();
    let l = 4.7; // λB = 2·3 − 4.7 = 1.3
    assert!(s2(&p, passive_stretch(&p, l), p.prestretch_2) < 0.0);
    assert!(s1(&p, passive_stretch(&p, l), p.prestretch_2) > 0.0);
    let margins = d.margins(l, 0.0);
    assert_eq!(margins.first_failure(), Some(FailureMode::LossOfTension2b));
}

/// The limit is found to full precision: its check holds at the limit stretch and fails
/// one float above it.
#[test]
fn limit_is_exact_to_the_last_bit() {
    for p in [
        REFERENCE_DEVICE,
        DeviceParams {
            breakdown_field: 30e6,
            ..REFERENCE_DEVICE
        },
        DeviceParams {
            prestretch_1: 0.7,
            prestretch_2: 2.8,
            length_passive: 0.05,
            jlim: None,
            ..REFERENCE_DEVICE
        },
    ] {
        let d = Device::new(p).unwrap();
        let limit = limit_of(p);
        let at = d.margins_on_branch(limit.at.stretch);
        assert_eq!(at.first_failure(), None);
        let above = d.margins_on_branch(next_up(limit.at.stretch));
        let margin = above.of(limit.mode);
        assert!(margin <= 0.0 || margin.is_nan(), "{above:?} at {limit:?}");
    }
}

/// No check fails anywhere between zero bias and the limit, on a grid 40× finer than the
/// core's scan.
#[test]
fn the_branch_is_safe_up_to_the_limit() {
    for p in [REFERENCE_DEVICE, neo_hookean_reference()] {
        let d = Device::new(p).unwrap();
        let limit = limit_of(p);
        for k in 0..=5000 {
            let l = p.prestretch_1 + (limit.at.stretch - p.prestretch_1) * f64::from(k) / 5000.0;
            assert_eq!(d.margins_on_branch(l).first_failure(), None, "λ = {l}");
        }
    }
}

#[test]
fn failure_mode_names_are_the_documented_ones() {
    let names: Vec<_> = FailureMode::ALL.iter().map(|m| m.name()).collect();
    assert_eq!(
        names,
        [
            "device_instability",
            "emi",
            "loss_of_tension_1",
            "loss_of_tension_2a",
            "loss_of_tension_2b",
            "breakdown",
            "stretch_limit"
        ]
    );
}

/// NaN anywhere counts as a failure, never as safe.
#[test]
fn nan_state_is_not_safe() {
    let d = Device::new(REFERENCE_DEVICE).unwrap();
    assert!(d.margins(f64::NAN, 0.0).first_failure().is_some());
    assert!(d.margins(2.1, f64::NAN).first_failure().is_some());
}
