//! The six checks of model.md §6 and the limit of the loading branch: each mode's limit
//! meets its own analytic boundary condition, computed here in plain SI.

mod common;

use common::*;
use de_resonator::model::material::Gent;
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

/// Stretch limit: I1 reaches Jlim in A or B (model.md §6.6 as written: I1 < Jlim).
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
    // The monitor's path (the breakdown's sign from squares, on the stretch terms): a NaN or
    // negative Φ̄², or a breakdown field that is not a positive number, fails too, in f32 as
    // flashed (2.1: inside the model, every check passing at zero bias).
    let d = Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap();
    assert_eq!(d.first_failure(2.1, 0.0), None);
    let terms = d.stretch_terms(2.1);
    for p2 in [f32::NAN, -1e-6, f32::NEG_INFINITY] {
        assert!(d.first_failure(2.1, p2).is_some(), "{p2}");
    }
    for b in [f32::NAN, 0.0, -1.0] {
        assert_eq!(
            terms.first_failure(0.0, b),
            Some(FailureMode::Breakdown),
            "{b}"
        );
    }
    let mut monitor = de_resonator::Monitor::new();
    assert!(monitor.observe(&d, 0, 2.1, f32::NAN).is_some());
}

/// Issue 12.2. A state with λB ≤ 0 (the bars at or past the far end: λ ≥ L1·λ1p/L1A) is
/// outside the model: loss of tension 1, never "no check failed" (s1 of a negative stretch
/// comes out positive), for the margins, the first failure and the monitor alike; and a
/// state with no length left in A (λ ≤ 0) the same.
#[test]
fn states_outside_the_model_are_loss_of_tension_1() {
    let p = REFERENCE_DEVICE;
    let d = Device::new(p).unwrap();
    let full = length_1(&p) * p.prestretch_1 / p.length_active;
    assert_eq!(passive_stretch(&p, full), 0.0);
    for stretch in [full, full + 0.5, 2.0 * full, 0.0, -1.0, f64::NAN] {
        for bias in [0.0, 0.1] {
            assert!(!d.in_model(stretch), "{stretch}");
            assert_eq!(
                d.first_failure(stretch, bias),
                Some(FailureMode::LossOfTension1),
                "{stretch}"
            );
            assert!(d.margins(stretch, bias).first_failure().is_some());
            let mut monitor = de_resonator::Monitor::new();
            assert_eq!(
                monitor.observe(&d, 0, stretch, bias),
                Some(FailureMode::LossOfTension1)
            );
        }
    }
}

/// Issue 12.2, model.md §6.3: along a trajectory A's own tension in direction 1,
/// s1(λ) − ε(Φ/H)²·λ·λ2p², is checked as well as B's. A state off the branch with A short
/// (λ = 0.8) and B taut (λB = 3.2), under a voltage 5% past the one that takes A's tension
/// to zero: every other check holds (by the plain-SI stresses here), and the first failure
/// is loss of tension 1.
#[test]
fn active_membrane_slack_in_direction_1_is_loss_of_tension_1() {
    let p = REFERENCE_DEVICE;
    let d = Device::new(p).unwrap();
    let (l, l2p) = (0.8, p.prestretch_2);
    let lb = passive_stretch(&p, l);
    assert!(s1(&p, lb, l2p) > 0.0 && s1(&p, l, l2p) > 0.0);
    // ε(Φ/H)²·λ·λ2p² = 1.05·s1(λ): A is in compression along 1.
    let field_squared = 1.05 * s1(&p, l, l2p) / (permittivity(&p) * l * l2p * l2p);
    let volts = field_squared.sqrt() * p.thickness;
    let bias = (volts / d.volts_per_unit()).powi(2);
    let tension_a = s1(&p, l, l2p) - permittivity(&p) * field_squared * l * l2p * l2p;
    assert!(tension_a < 0.0);
    let margins = d.margins(l, bias);
    for mode in FailureMode::ALL {
        if mode != FailureMode::LossOfTension1 {
            assert!(margins.of(mode) > 0.0, "{mode}: {margins:?}");
        }
    }
    let expected = tension_a / p.shear_modulus;
    let got = margins.of(FailureMode::LossOfTension1);
    assert!((got - expected).abs() < 1e-9, "{got} vs {expected}");
    assert_eq!(d.first_failure(l, bias), Some(FailureMode::LossOfTension1));
}

/// Issue 12.6. The f32 limit (as on the chip) against the f64 limit of the same device (the
/// f32 parameters, as flashed), on random devices of which two in three have their limit
/// just past the pre-stretch (breakdown, or loss of tension 2a on a nearly slack membrane):
/// within 1e-6 in volts, the controller's guard (1e-5) well above it.
#[test]
fn f32_limits_agree_with_f64_also_just_past_the_prestretch() {
    let mut rng = Rng(0x5eed_0012);
    let (mut checked, mut near, mut worst) = (0, 0, 0.0f64);
    while checked < 3000 {
        let p = random_device(&mut rng);
        let (Ok(_), Ok(d32)) = (Device::new(p), Device::new(p.cast::<f32>())) else {
            continue;
        };
        checked += 1;
        let (l64, l32) = (limit_of(p), *Tuner::new(d32).limit());
        near += usize::from(l64.at.offset < 1e-4 * p.prestretch_1);
        let error = (f64::from(l32.at.volts) / l64.at.volts - 1.0).abs();
        worst = worst.max(error);
        assert!(error < 1e-6, "{error:e}: {p:?}\n{l64:?}\n{l32:?}");
        assert_eq!(l32.mode, l64.mode, "{p:?}");
    }
    assert!(near > 1000, "{near} limits near the pre-stretch");
    println!("{checked} devices, {near} with the limit within 1e-4 of λ1p: worst {worst:e}");
}

/// Issue 12.7. A margin with a NaN part fails its check, whichever part is NaN: the
/// safety minimum propagates NaN (the ordinary `min` does not).
#[test]
fn a_nan_part_fails_its_margin_in_either_position() {
    use de_resonator::model::material::Hessian;
    use de_resonator::{Margins, Real};
    for (a, b) in [(f64::NAN, 1.0), (1.0, f64::NAN), (f64::NAN, f64::NAN)] {
        assert!(a.min_margin(b).is_nan());
        assert!((a as f32).min_margin(b as f32).is_nan());
    }
    assert_eq!(2.0f64.min_margin(1.0), 1.0);
    assert_eq!((-1.0f64).min_margin(1.0), -1.0);
    // EMI's definiteness, min(d11, det): NaN in d11, and NaN in det (through d22).
    for h in [
        Hessian {
            d11: f64::NAN,
            d12: 0.0,
            d22: 1.0,
        },
        Hessian {
            d11: 1.0,
            d12: 0.0,
            d22: f64::NAN,
        },
    ] {
        assert!(h.definiteness().is_nan(), "{h:?}");
    }
    // Any NaN margin is a failure of that check.
    let d = Device::new(REFERENCE_DEVICE).unwrap();
    let safe = d.margins_on_branch(2.1);
    assert_eq!(safe.first_failure(), None);
    for mode in FailureMode::ALL {
        let mut m = safe;
        m.values[mode as usize] = f64::NAN;
        assert_eq!(Margins { values: m.values }.first_failure(), Some(mode));
    }
    // The stretch limit takes the least of A's and B's: a NaN in either fails it.
    let g = Gent::<f64>::with_jlim(120.0);
    for (a, b) in [(f64::NAN, 2.0), (2.0, f64::NAN)] {
        let lock = g
            .lock_up_margin(a, 2.0)
            .min_margin(g.lock_up_margin(b, 2.0));
        assert!(lock.is_nan());
    }
}

/// Every margin of model.md §6, on and off the branch, against its plain-SI value (over μ,
/// fields over √(μ/ε)), at states with both membranes taut: A's and B's stresses, the field,
/// the invariants; the stiffness and the Hessian's definiteness by finite differences of the
/// plain force law and energy.
#[test]
fn every_margin_is_its_plain_si_value() {
    let p = REFERENCE_DEVICE;
    let d = Device::new(p).unwrap();
    let (mu, l2p, eps) = (p.shear_modulus, p.prestretch_2, permittivity(&p));
    let jlim = p.jlim.unwrap();
    for (l, volts) in [(2.1, 3000.0), (2.25, 8000.0), (1.9, 6000.0), (2.3, 500.0)] {
        let e0 = volts / p.thickness;
        let lb = passive_stretch(&p, l);
        let bias = (volts / d.volts_per_unit()).powi(2);
        let m = d.margins(l, bias);
        let field = e0 * l * l2p;
        let expected = [
            (
                FailureMode::DeviceInstability,
                omega_squared_fd(&p, l, volts) / (d.rad_per_s_per_unit().powi(2)),
            ),
            (
                FailureMode::LossOfTension1,
                (s1(&p, lb, l2p)).min(s1(&p, l, l2p) - eps * e0 * e0 * l * l2p * l2p) / mu,
            ),
            (
                FailureMode::LossOfTension2a,
                (l2p * s2(&p, l, l2p) - eps * field * field) / mu,
            ),
            (FailureMode::LossOfTension2b, l2p * s2(&p, lb, l2p) / mu),
            (
                FailureMode::Breakdown,
                (p.breakdown_field - field) * (eps / mu).sqrt(),
            ),
            (
                FailureMode::StretchLimit,
                (1.0 - first_invariant(l, l2p) / jlim).min(1.0 - first_invariant(lb, l2p) / jlim),
            ),
        ];
        for (mode, value) in expected {
            let got = m.of(mode);
            assert!(
                (got - value).abs() <= 1e-6 * value.abs().max(1e-3),
                "{mode} at λ {l}, {volts} V: {got} vs {value}"
            );
        }
        // EMI: the Hessian of F = W − ½ε E0² λ1² λ2² over μ, by differences of the energy.
        let f = |a: f64, b: f64| (energy(&p, a, b) - 0.5 * eps * e0 * e0 * a * a * b * b) / mu;
        let h = 1e-4;
        let faa = (f(l + h, l2p) - 2.0 * f(l, l2p) + f(l - h, l2p)) / (h * h);
        let fbb = (f(l, l2p + h) - 2.0 * f(l, l2p) + f(l, l2p - h)) / (h * h);
        let fab = (f(l + h, l2p + h) - f(l + h, l2p - h) - f(l - h, l2p + h) + f(l - h, l2p - h))
            / (4.0 * h * h);
        let definiteness = faa.min(faa * fbb - fab * fab);
        let got = m.of(FailureMode::Emi);
        assert!(
            (got - definiteness).abs() < 1e-4 * definiteness.abs(),
            "{got} vs {definiteness}"
        );
        // On the branch, at the stretch this bias holds, the same values.
        let held = d.stretch_for_bias(volts, 2.5).unwrap();
        let on = d.margins_on_branch(held);
        let off = d.margins(held, bias);
        for mode in FailureMode::ALL {
            let (a, b) = (on.of(mode), off.of(mode));
            assert!(
                (a - b).abs() <= 1e-6 * b.abs().max(1e-3),
                "{mode}: {a} vs {b}"
            );
        }
    }
}

/// A margin of exactly zero fails its check (the boundary is not safe), and a state outside
/// the model has a negative tension margin, not only undefined others.
#[test]
fn zero_is_not_safe_and_outside_is_negative() {
    use de_resonator::Margins;
    let safe = Device::new(REFERENCE_DEVICE)
        .unwrap()
        .margins_on_branch(2.1);
    for mode in FailureMode::ALL {
        let mut values = safe.values;
        values[mode as usize] = 0.0;
        assert_eq!(Margins { values }.first_failure(), Some(mode));
    }
    assert!(Margins::<f64>::outside_model().of(FailureMode::LossOfTension1) < 0.0);
}

/// The bounds the scan and the sensor use, from their definitions: the plausible stretches
/// (−λfull, 2·λfull) with λfull = L1·λ1p/L1A; the model's range from ½λ2p^(−1/2) (or λ1p);
/// the scan's end, the least of B slack (λB = ½λ2p^(−1/2)), √Jlim, and the breakdown bound of
/// `Device::scan_end_stretch`'s doc, never below λ1p.
#[test]
fn the_bounds_are_their_definitions() {
    for p in [
        REFERENCE_DEVICE,
        neo_hookean_reference(),
        DeviceParams {
            breakdown_field: 20e6,
            ..REFERENCE_DEVICE
        },
        DeviceParams {
            jlim: Some(9.0),
            ..REFERENCE_DEVICE
        },
        non_monotone_device(),
    ] {
        let d = Device::new(p).unwrap();
        let (l1p, l2p) = (p.prestretch_1, p.prestretch_2);
        let full = length_1(&p) * l1p / p.length_active;
        let (low, high) = d.plausible_stretch();
        assert!((low + full).abs() < 1e-12 && (high - 2.0 * full).abs() < 1e-12);
        let slack = 0.5 / l2p.sqrt();
        let (start, end) = d.model_range();
        assert!((start - slack.min(l1p)).abs() < 1e-12);
        let b_slack = l1p + (l1p - slack) * p.length_passive / p.length_active;
        let locked = p.jlim.map_or(f64::INFINITY, f64::sqrt);
        let k = 1.0 / (l1p.powi(3) * l2p * l2p) + s1(&p, l1p, l2p) / p.shear_modulus;
        let eb = p.breakdown_field * (permittivity(&p) / p.shear_modulus).sqrt();
        let broken = (k + (k * k + 4.0 * eb * eb).sqrt()) / 2.0 * 1.001;
        let expected = b_slack.min(locked).min(broken).max(l1p);
        assert!(
            (end - expected).abs() < 1e-12 * expected,
            "{end} vs {expected}"
        );
        assert_eq!(d.scan_end_stretch(), end);
    }
}

/// Two checks failing in one cell of the scan: the earlier one is the limit. Breakdown set
/// just below the field at the EMI limit (0.999 of it) comes first, at E = E_B.
#[test]
fn two_failures_in_one_cell_report_the_earlier() {
    let emi = limit_of(REFERENCE_DEVICE);
    assert_eq!(emi.mode, FailureMode::Emi);
    let p = REFERENCE_DEVICE;
    let field_at_emi = emi.at.volts * emi.at.stretch * p.prestretch_2 / p.thickness;
    let q = DeviceParams {
        breakdown_field: 0.999 * field_at_emi,
        ..p
    };
    let limit = limit_of(q);
    assert_eq!(limit.mode, FailureMode::Breakdown);
    let field = limit.at.volts * limit.at.stretch * q.prestretch_2 / q.thickness;
    assert!((field / q.breakdown_field - 1.0).abs() < 1e-9, "{field}");
    assert!(limit.at.stretch < emi.at.stretch);
}

/// The trim's estimate is the device flashed with another μ, and the monitor checks it with
/// the flashed device's stretch terms (the tick's budget): on random devices, μ scaled by
/// 1/4 to 4, at random stretches in and out of the model and random voltages, the shared
/// terms give the estimate's own margins bit for bit (every stress is in units of μ; the
/// bias and the breakdown field carry μ, and they are the estimate's). A device that also
/// differs elsewhere (λ2p) is not taken for one that shares them.
#[test]
fn a_device_differing_only_in_mu_shares_the_stretch_terms() {
    let mut rng = Rng(0x5eed_7e55);
    let (mut checked, mut agreed) = (0, 0);
    while checked < 300 {
        let Some((p, flashed, scaled, estimate)) = device_and_estimate(&mut rng) else {
            continue;
        };
        assert!(flashed.differs_only_in_modulus(&estimate));
        let other = DeviceParams {
            prestretch_2: p.prestretch_2 * 1.01,
            ..scaled
        };
        if let Ok(other) = Device::new(other.cast::<f32>()) {
            assert!(!flashed.differs_only_in_modulus(&other));
        }
        let (low, high) = flashed.plausible_stretch();
        for _ in 0..20 {
            let stretch = rng.range(f64::from(low), f64::from(high)) as f32;
            let volts = rng.range(0.0, 3.0) as f32 * flashed.volts_per_unit();
            let p2 = (volts / estimate.volts_per_unit()).powi(2);
            let own = estimate.margins(stretch, p2);
            let shared = flashed
                .stretch_terms(stretch)
                .margins(p2, estimate.breakdown_field_dimless());
            let bits = |m: &de_resonator::Margins<f32>| m.values.map(f32::to_bits);
            assert_eq!(bits(&own), bits(&shared), "{p:?} at {stretch}, {volts} V");
            let first = estimate.first_failure(stretch, p2);
            assert_eq!(
                first,
                flashed
                    .stretch_terms(stretch)
                    .first_failure(p2, estimate.breakdown_field_dimless())
            );
            // The monitor's first failure (the breakdown's sign from squares) is the
            // margins' own, but within a rounding of the breakdown's boundary (outside the
            // model both say loss of tension 1, the margins' NaN elsewhere aside).
            let breakdown = own.of(FailureMode::Breakdown);
            if !estimate.in_model(stretch) {
                assert_eq!(first, Some(FailureMode::LossOfTension1));
            } else if breakdown.abs() > 1e-5 * estimate.breakdown_field_dimless() {
                assert_eq!(first, own.first_failure(), "{p:?} at {stretch}, {volts} V");
                agreed += 1;
            }
        }
        checked += 1;
    }
    assert!(
        agreed > 1_000,
        "{agreed} states in the model, off the breakdown's boundary"
    );
}

/// A random valid device (f32, as flashed) and an estimate of it that differs only in μ
/// (μ/4 to 4μ) and the damping (which no check reads); `None` where either is not valid.
#[allow(clippy::type_complexity)]
fn device_and_estimate(
    rng: &mut Rng,
) -> Option<(
    DeviceParams<f64>,
    Device<f32>,
    DeviceParams<f64>,
    Device<f32>,
)> {
    let p = random_device(rng);
    let flashed = Device::new(p.cast::<f32>()).ok()?;
    let scaled = DeviceParams {
        shear_modulus: p.shear_modulus * rng.log_range(0.25, 4.0),
        damping: rng.range(0.0, 1.0),
        ..p
    };
    let estimate = Device::new(scaled.cast::<f32>()).ok()?;
    Some((p, flashed, scaled, estimate))
}

/// The monitor's one check for two devices that differ only in μ (`StretchTerms::both_pass`)
/// passes exactly when each device's own checks pass, on random devices, estimates of μ/4 to
/// 4μ, stretches in and out of the model and voltages up to three times the unit, and near
/// the pre-stretch at low voltages (where most pass): both outcomes counted.
#[test]
fn one_check_passes_exactly_when_both_devices_pass() {
    let mut rng = Rng(0xb07_4a55);
    let (mut both, mut one_fails, mut devices) = (0, 0, 0);
    while devices < 300 {
        let Some((p, flashed, scaled, estimate)) = device_and_estimate(&mut rng) else {
            continue;
        };
        devices += 1;
        let (low, high) = flashed.plausible_stretch();
        for k in 0..40 {
            // Half anywhere, half near the pre-stretch at low voltages (where most pass).
            let (stretch, volts) = if k % 2 == 0 {
                (
                    rng.range(f64::from(low), f64::from(high)),
                    rng.range(0.0, 3.0),
                )
            } else {
                let l1p = f64::from(flashed.prestretch_1());
                (l1p * rng.range(0.9, 1.3), rng.range(0.0, 0.5))
            };
            let (stretch, volts) = (stretch as f32, volts as f32 * flashed.volts_per_unit());
            let of = |d: &Device<f32>| {
                let p = volts / d.volts_per_unit();
                (p * p, d.breakdown_field_dimless())
            };
            let (f, e) = (of(&flashed), of(&estimate));
            let (larger, smaller) = if e.0 > f.0 { (e, f) } else { (f, e) };
            let each = flashed.first_failure(stretch, f.0).is_none()
                && estimate.first_failure(stretch, e.0).is_none();
            let one = flashed.stretch_terms(stretch).both_pass(larger, smaller);
            assert_eq!(
                one, each,
                "{p:?}, μ {} at {stretch}, {volts} V",
                scaled.shear_modulus
            );
            if each {
                both += 1;
            } else {
                one_fails += 1;
            }
        }
    }
    eprintln!("{both} pass, {one_fails} fail");
    assert!(
        both > 500 && one_fails > 500,
        "{both} pass, {one_fails} fail"
    );
}
