//! Tuning (model.md §7): the bias reproduces the target, checked against the plain-SI
//! force law; it is the smallest such bias; it lies inside the safe region with the margin.

mod common;

use common::*;
use de_resonator::{Device, DeviceParams, TuneError, Tuner, REFERENCE_DEVICE};
use proptest::prelude::*;

/// f(Φ) rises with the bias.
fn rising() -> DeviceParams<f64> {
    DeviceParams {
        prestretch_1: 1.24,
        prestretch_2: 1.53,
        length_active: 0.0423,
        length_passive: 0.0173,
        jlim: None,
        ..REFERENCE_DEVICE
    }
}

fn tuner(p: DeviceParams<f64>) -> Tuner<f64> {
    Tuner::new(Device::new(p).unwrap())
}

/// The first stretch on a fine grid where the independent frequency crosses the target.
fn first_crossing(p: &DeviceParams<f64>, target: f64, max_stretch: f64) -> (f64, f64) {
    let n = 20_000;
    let grid = |k: usize| p.prestretch_1 + (max_stretch - p.prestretch_1) * k as f64 / n as f64;
    let f = |l: f64| frequency_fd(p, l, bias_squared(p, l).max(0.0).sqrt()) - target;
    let side = f(grid(0)) > 0.0;
    let k = (1..=n)
        .find(|&k| (f(grid(k)) > 0.0) != side)
        .expect("a crossing");
    (grid(k - 1), grid(k))
}

#[test]
fn non_monotone_device_takes_the_smallest_bias() {
    let p = non_monotone_device();
    let t = tuner(p);
    let range = t.tunable_range(0.05).unwrap();
    let zero = t.zero_bias().natural_frequency_hz;
    // The minimum is inside the branch, the maximum at its allowed end.
    assert!(
        range.low_hz < zero && range.high_hz > zero,
        "{range:?}, f0 {zero}"
    );
    assert!(range.low_hz < range.max_bias.natural_frequency_hz);
    assert_eq!(range.high_hz, range.max_bias.natural_frequency_hz);
    // Between the minimum and f0 two stretches give each target: the first is taken.
    // Above f0, only the rising side reaches.
    for u in [0.001, 0.1, 0.5, 0.9] {
        for target in [
            range.low_hz + u * (zero - range.low_hz),
            zero + u * (range.high_hz - zero),
        ] {
            let bias = t.tune(target, 0.05).unwrap();
            let (lo, hi) = first_crossing(&p, target, range.max_bias.stretch);
            assert!(
                bias.stretch >= lo - 1e-9 && bias.stretch <= hi + 1e-9,
                "{target}: {bias:?} not in [{lo}, {hi}]"
            );
        }
    }
}

#[test]
fn rising_device_tunes_upwards_only() {
    let t = tuner(rising());
    let zero = t.zero_bias().natural_frequency_hz;
    let range = t.tunable_range(0.05).unwrap();
    assert_eq!(range.low_hz, zero);
    assert!(range.high_hz > zero);
    let target = 0.5 * (range.low_hz + range.high_hz);
    let bias = t.tune(target, 0.05).unwrap();
    assert!(rel(frequency_fd(&rising(), bias.stretch, bias.volts), target) < 1e-7);
    match t.tune(0.99 * zero, 0.05) {
        Err(TuneError::OutOfRange {
            low_hz, high_hz, ..
        }) => {
            assert_eq!((low_hz, high_hz), (range.low_hz, range.high_hz))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn ends_of_the_range_are_reachable() {
    for p in [REFERENCE_DEVICE, non_monotone_device(), rising()] {
        let t = tuner(p);
        let range = t.tunable_range(0.05).unwrap();
        for target in [range.low_hz, range.high_hz] {
            let bias = t.tune(target, 0.05).unwrap();
            assert!(rel(bias.natural_frequency_hz, target) < 1e-12);
            assert!(bias.volts <= range.max_bias.volts);
        }
    }
}

#[test]
fn margin_scales_the_highest_bias() {
    let t = tuner(REFERENCE_DEVICE);
    let limit_volts = t.limit().at.volts;
    for margin in [0.0, 0.05, 0.2, 0.5] {
        let max = t.max_bias(margin).unwrap().volts;
        assert!(
            rel(max, (1.0 - margin) * limit_volts) < 1e-12,
            "{margin}: {max}"
        );
    }
    // A margin that excludes the target turns a reachable target into an error.
    let target = 0.5 * (t.limit().at.natural_frequency_hz + t.tunable_range(0.05).unwrap().low_hz);
    assert!(t.tune(target, 0.0).is_ok());
    assert!(matches!(
        t.tune(target, 0.05),
        Err(TuneError::OutOfRange { .. })
    ));
}

/// Devices drawn across a wide span of materials and geometries; invalid ones are skipped.
fn any_device() -> impl Strategy<Value = DeviceParams<f64>> {
    (
        (0.7f64..4.5, 0.7f64..4.5, 0.005f64..0.06, 0.005f64..0.06),
        (1e4f64..1e6, 2.0f64..10.0, 500.0f64..2000.0, 1e-4f64..3e-3),
        (0.01f64..0.1, 0.0f64..0.02, 2e7f64..3e8),
        prop::option::of(1.0f64..200.0),
    )
        .prop_map(
            |((l1p, l2p, la, lb), (mu, er, rho, h), (w, m, eb), jlim_above)| {
                let i1 = first_invariant(l1p, l2p);
                DeviceParams {
                    shear_modulus: mu,
                    jlim: jlim_above.map(|j| i1 + j),
                    relative_permittivity: er,
                    density: rho,
                    breakdown_field: eb,
                    thickness: h,
                    length_active: la,
                    length_passive: lb,
                    width: w,
                    bar_mass: m,
                    prestretch_1: l1p,
                    prestretch_2: l2p,
                    damping: 0.0,
                }
            },
        )
        .prop_filter("valid device", |p| Device::new(*p).is_ok())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The tuned bias reproduces the target (second method: the plain-SI force law of
    /// model.md §4 is at rest there, and −∂λ''/∂λ gives the target frequency), stays within
    /// (1 − margin)·Φlimit, and every check holds along the whole path up to it.
    #[test]
    fn tuned_bias_hits_the_target_inside_the_safe_region(
        p in any_device(), margin in 0.0f64..0.3, u in 0.0f64..=1.0,
    ) {
        let t = tuner(p);
        let range = t.tunable_range(margin).unwrap();
        let target = range.low_hz + u * (range.high_hz - range.low_hz);
        let bias = t.tune(target, margin).unwrap();
        let scale = p.width * p.thickness * p.shear_modulus / effective_mass(&p);
        prop_assert!(acceleration(&p, bias.stretch, bias.volts).abs() < 1e-10 * scale);
        let f = frequency_fd(&p, bias.stretch, bias.volts);
        prop_assert!(rel(f, target) < 1e-6, "f {} target {}", f, target);
        prop_assert!(bias.volts <= (1.0 - margin) * t.limit().at.volts * (1.0 + 1e-15));
        let d = t.device();
        for k in 0..=200 {
            let l = p.prestretch_1 + (bias.stretch - p.prestretch_1) * f64::from(k) / 200.0;
            prop_assert_eq!(d.margins_on_branch(l).first_failure(), None);
        }
    }

    /// Targets outside the range are refused with the range; never a bias.
    #[test]
    fn targets_outside_the_range_are_refused(p in any_device(), over in 1e-6f64..1.0) {
        let t = tuner(p);
        let range = t.tunable_range(0.05).unwrap();
        for target in [range.high_hz * (1.0 + over), range.low_hz * (1.0 - over)] {
            let refused = matches!(
                t.tune(target, 0.05),
                Err(TuneError::OutOfRange { low_hz, high_hz, .. })
                    if low_hz == range.low_hz && high_hz == range.high_hz
            );
            prop_assert!(refused);
        }
    }

    /// f32, as on the target, on the device as f32 holds it: the f32 bias, evaluated in f64
    /// physics, gives the target within 2e-6 relative and never exceeds the f64 limit with
    /// the margin. Where the f32 range does not hold the target (a range of 1e-6 relative
    /// or so, near f32's resolution), the refusal with that range is the right answer.
    #[test]
    fn f32_tuning_is_accurate(p in any_device(), u in 0.02f64..0.98) {
        let p = p.cast::<f32>().cast::<f64>();
        let t64 = tuner(p);
        let t32 = Tuner::new(Device::new(p.cast::<f32>()).unwrap());
        let range = t64.tunable_range(0.05).unwrap();
        let target = range.low_hz + u * (range.high_hz - range.low_hz);
        match t32.tune(target as f32, 0.05) {
            Ok(bias) => {
                let volts = f64::from(bias.volts);
                let d = t64.device();
                let offset = d.offset_for_bias(volts, t64.limit().at.offset).unwrap();
                prop_assert!(rel(d.natural_frequency_hz_at(offset), target) < 2e-6);
                prop_assert!(volts <= range.max_bias.volts * (1.0 + 1e-5));
            }
            Err(TuneError::OutOfRange { low_hz, high_hz, .. }) => {
                let t = target as f32;
                prop_assert!(!(t >= low_hz && t <= high_hz), "{} in [{}, {}]", t, low_hz, high_hz);
            }
            Err(e) => prop_assert!(false, "{}", e),
        }
    }
}
