//! Every error path of the core: bad parameters name their field, bad tuning requests say
//! what is wrong. Nothing panics.

use de_resonator::{
    Decimal, Device, DeviceParams, Field, ParamError, Problem, TuneError, Tuner, REFERENCE_DEVICE,
};

type Setter = fn(&mut DeviceParams<f64>, f64);

/// Every field with a setter, and whether zero is allowed.
fn fields() -> Vec<(Field, Setter, bool)> {
    vec![
        (Field::ShearModulus, |p, v| p.shear_modulus = v, false),
        (Field::Jlim, |p, v| p.jlim = Some(v), false),
        (
            Field::RelativePermittivity,
            |p, v| p.relative_permittivity = v,
            false,
        ),
        (Field::Density, |p, v| p.density = v, false),
        (Field::BreakdownField, |p, v| p.breakdown_field = v, false),
        (Field::Thickness, |p, v| p.thickness = v, false),
        (Field::LengthActive, |p, v| p.length_active = v, false),
        (Field::LengthPassive, |p, v| p.length_passive = v, false),
        (Field::Width, |p, v| p.width = v, false),
        (Field::BarMass, |p, v| p.bar_mass = v, true),
        (Field::Prestretch1, |p, v| p.prestretch_1 = v, false),
        (Field::Prestretch2, |p, v| p.prestretch_2 = v, false),
        (Field::Damping, |p, v| p.damping = v, true),
    ]
}

fn with(set: Setter, value: f64) -> Result<Device<f64>, ParamError> {
    let mut p = REFERENCE_DEVICE;
    set(&mut p, value);
    Device::new(p)
}

#[test]
fn nan_and_infinite_values_name_the_field() {
    for (field, set, _) in fields() {
        for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(
                with(set, value).unwrap_err(),
                ParamError {
                    field,
                    problem: Problem::NotFinite
                },
                "{field:?} = {value}"
            );
        }
    }
}

#[test]
fn zero_and_negative_values_name_the_field() {
    for (field, set, zero_allowed) in fields() {
        let problem = if zero_allowed {
            Problem::Negative
        } else {
            Problem::NotPositive
        };
        assert_eq!(with(set, -1.0).unwrap_err(), ParamError { field, problem });
        assert_eq!(with(set, -0.0).is_ok(), zero_allowed, "{field:?}");
        assert_eq!(with(set, 0.0).is_ok(), zero_allowed, "{field:?}");
    }
}

#[test]
fn massless_bars_and_damping_are_valid() {
    let p = DeviceParams {
        bar_mass: 0.0,
        damping: 0.01,
        ..REFERENCE_DEVICE
    };
    assert!(Device::new(p).is_ok());
}

/// λ1p²·λ2p ≤ 1 leaves B slack in direction 1 at zero bias; λ2p²·λ1p ≤ 1 direction 2.
#[test]
fn pre_stretch_without_tension_at_zero_bias() {
    let slack_1 = DeviceParams {
        prestretch_1: 0.5,
        prestretch_2: 4.0, // 0.25·4 = 1: exactly slack
        ..REFERENCE_DEVICE
    };
    assert_eq!(
        Device::new(slack_1).unwrap_err(),
        ParamError {
            field: Field::Prestretch1,
            problem: Problem::NoTension1AtZeroBias
        }
    );
    let slack_2 = DeviceParams {
        prestretch_1: 2.0,
        prestretch_2: 0.7, // 0.49·2 = 0.98
        ..REFERENCE_DEVICE
    };
    assert_eq!(
        Device::new(slack_2).unwrap_err(),
        ParamError {
            field: Field::Prestretch2,
            problem: Problem::NoTension2AtZeroBias
        }
    );
}

/// I1 at the reference pre-stretch is 4 + 4 + 1/16 = 8.0625.
#[test]
fn jlim_already_reached_by_the_pre_stretch() {
    for jlim in [8.0, 8.0625, 5.0] {
        let p = DeviceParams {
            jlim: Some(jlim),
            ..REFERENCE_DEVICE
        };
        assert_eq!(
            Device::new(p).unwrap_err(),
            ParamError {
                field: Field::Jlim,
                problem: Problem::StretchLimitAtZeroBias
            }
        );
    }
    let p = DeviceParams {
        jlim: Some(8.07),
        ..REFERENCE_DEVICE
    };
    assert!(Device::new(p).is_ok());
}

/// Values that are finite in f64 but overflow f32 are refused on the target's type.
#[test]
fn values_too_large_for_f32() {
    let p = DeviceParams {
        shear_modulus: 1e100,
        ..REFERENCE_DEVICE
    };
    assert!(Device::new(p).is_ok());
    assert_eq!(
        Device::new(p.cast::<f32>()).unwrap_err(),
        ParamError {
            field: Field::ShearModulus,
            problem: Problem::NotFinite
        }
    );
    // Finite inputs whose voltage scale H·√(μ/ε) is not: ε = εr·ε0 underflows f32.
    let p = DeviceParams {
        relative_permittivity: 1e-36,
        ..REFERENCE_DEVICE
    };
    assert!(Device::new(p).is_ok());
    let e = Device::new(p.cast::<f32>()).unwrap_err();
    assert_eq!(
        e.problem,
        Problem::DerivedNotFinite {
            scale: "H·√(μ/ε)"
        }
    );
    assert!(e.to_string().contains("H·√(μ/ε)"), "{e}");
}

#[test]
fn messages_name_the_device_file_key() {
    for (field, set, _) in fields() {
        let message = with(set, f64::NAN).unwrap_err().to_string();
        assert!(message.contains(&format!("`{}`", field.key())), "{message}");
    }
    let message = with(|p, v| p.prestretch_1 = v, 0.3)
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("prestretch_1") && message.contains("slack"),
        "{message}"
    );
}

fn reference() -> Tuner<f64> {
    Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
}

#[test]
fn bad_targets_are_refused() {
    let t = reference();
    for target in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -44.0] {
        match t.tune(target, 0.05) {
            Err(TuneError::InvalidTarget { target_hz }) => {
                assert!(target_hz.to_bits() == target.to_bits())
            }
            other => panic!("{target}: {other:?}"),
        }
    }
}

#[test]
fn bad_margins_are_refused() {
    let t = reference();
    for margin in [f64::NAN, -0.01, 1.0, 2.0, f64::INFINITY] {
        let refused = |r: Result<_, TuneError<f64>>| matches!(r, Err(TuneError::InvalidMargin { margin: m }) if m.to_bits() == margin.to_bits());
        assert!(refused(t.tune(44.0, margin).map(|_| ())), "{margin}");
        assert!(refused(t.tunable_range(margin).map(|_| ())));
        assert!(refused(t.max_bias(margin).map(|_| ())));
    }
}

#[test]
fn out_of_range_carries_the_range_and_says_so() {
    let t = reference();
    let range = t.tunable_range(0.05).unwrap();
    let e = t.tune(50.0, 0.05).unwrap_err();
    assert_eq!(
        e,
        TuneError::OutOfRange {
            target_hz: 50.0,
            low_hz: range.low_hz,
            high_hz: range.high_hz
        }
    );
    let message = e.to_string();
    assert!(
        message.contains("50 Hz") && message.contains("tunable range"),
        "{message}"
    );
    // The range's ends as messages write numbers (12 significant digits for f64).
    let high = Decimal(range.high_hz).to_string();
    assert!(message.contains(&high), "{message}");
    let back: f64 = high.parse().unwrap();
    assert!(
        (back - range.high_hz).abs() <= 1e-11 * range.high_hz,
        "{high}"
    );
}

/// The same inputs in f32, as the firmware sees them.
#[test]
fn f32_paths_refuse_the_same_inputs() {
    let t = Tuner::new(Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap());
    assert!(matches!(
        t.tune(f32::NAN, 0.05),
        Err(TuneError::InvalidTarget { .. })
    ));
    assert!(matches!(
        t.tune(44.0, f32::NAN),
        Err(TuneError::InvalidMargin { .. })
    ));
    assert!(matches!(
        t.tune(1e30, 0.05),
        Err(TuneError::OutOfRange { .. })
    ));
    assert!(matches!(
        t.tune(1e-30, 0.05),
        Err(TuneError::OutOfRange { .. })
    ));
}

mod arbitrary_input {
    use super::*;
    use proptest::prelude::*;

    /// Any f64 at all, special values often.
    fn any_f64() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(0.0),
            Just(-1.0),
            Just(f64::MAX),
            Just(f64::MIN_POSITIVE),
            -1e3f64..1e3,
            any::<f64>(),
        ]
    }

    /// The reference device with μ and the pre-stretches scaled, and a few fields set to
    /// anything at all.
    fn perturbed() -> impl Strategy<Value = DeviceParams<f64>> {
        (
            (0.5f64..2.0, 0.3f64..2.0, 0.3f64..2.0),
            prop::collection::vec((0usize..13, any_f64()), 0..4),
        )
            .prop_map(|((mu, l1, l2), wild)| {
                let mut p = REFERENCE_DEVICE;
                p.shear_modulus *= mu;
                p.prestretch_1 *= l1;
                p.prestretch_2 *= l2;
                let setters = fields();
                for (i, value) in wild {
                    (setters[i].1)(&mut p, value);
                }
                p
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        /// Whatever the parameters, target and margin: no panic, and a bias that comes back
        /// is finite, within the margin and safe, in f64 and in f32.
        #[test]
        fn no_panic_and_any_bias_is_safe(
            p in perturbed(), target in any_f64(), margin in any_f64(), u in 0.0f64..1.0,
        ) {
            if let Ok(d) = Device::new(p) {
                let t = Tuner::new(d);
                let _ = t.tune(target, margin);
                if let Ok(range) = t.tunable_range(0.05) {
                    let target = range.low_hz + u * (range.high_hz - range.low_hz);
                    let bias = t.tune(target, 0.05).unwrap();
                    prop_assert!(bias.volts.is_finite());
                    prop_assert!(bias.volts <= 0.95 * t.limit().at.volts * (1.0 + 1e-15));
                    prop_assert_eq!(d.margins_on_branch(bias.stretch).first_failure(), None);
                }
            }
            if let Ok(d) = Device::new(p.cast::<f32>()) {
                let t = Tuner::new(d);
                let _ = t.tune(target as f32, margin as f32);
                if let Ok(bias) = t.tune(t.zero_bias().natural_frequency_hz, 0.05) {
                    prop_assert!(bias.volts.is_finite());
                    prop_assert_eq!(d.margins_on_branch(bias.stretch).first_failure(), None);
                }
            }
        }
    }
}
