//! The controller's watch at run time, as the firmware runs it: every fault comes down at the
//! slew rate and says so once, samples outside the model are refused, the leakage watch, and
//! no input of any kind takes the command above the limit (a property test).

mod common;

use common::{amplifier, reference_table, start_reference as start};

use de_resonator::{
    Controller, DacCode, Event, Fault, FaultStage, Inputs, Output, Phase, Settings,
    REFERENCE_DEVICE,
};
use proptest::prelude::*;

/// After a fault from `from_volts` (the last voltage sent), the output goes down by the slew
/// rate's step a tick (issue 11: no faster, since a step down rings the membrane toward loss
/// of tension), within one DAC step of the straight line, reaches 0 V in the ticks the slew
/// needs and stays there; nothing more is said.
fn assert_descends(c: &mut Controller, first: Output, from_volts: f32) {
    let settings = *c.settings();
    let step_volts = settings.slew_volts_per_second / settings.tick_hz;
    let lsb_volts = 2.5 * 4000.0 / 65536.0;
    let needed = (from_volts / step_volts).ceil() as u32;
    let mut out = first;
    for n in 1..=needed + 100 {
        let line = (from_volts - step_volts * n as f32).max(0.0);
        assert!(
            (out.volts - line).abs() <= lsb_volts,
            "descent tick {n}: {} V, the slew's line {line} V",
            out.volts
        );
        if n >= needed {
            assert_eq!(out.code, DacCode(0), "descent tick {n}");
        }
        out = c.tick(Inputs::stretch(f32::NAN));
        assert_eq!(out.event, None);
    }
    assert_eq!(c.phase(), Phase::Faulted);
}

#[test]
fn faults_at_run_time_come_down_at_the_slew_rate_and_say_so_once() {
    // The reference settings ramp at 10 kV/s, 1 kHz: 10 V a tick.
    let mut c = start(Settings::for_target(44.0)).unwrap();
    // Samples near the pre-stretch while the ramp starts: safe, no event.
    for k in 0..100 {
        let stretch = 2.0 + 1e-6 * k as f32;
        assert_eq!(c.tick(Inputs::stretch(stretch)).event, None);
    }
    let sent = c.last_volts();
    // Tick 0 at 0 V, then 10 V a tick: 990 V at tick 99.
    assert!((sent - 990.0).abs() <= 0.2, "{sent} V after 100 ticks");
    let out = c.tick(Inputs::stretch(f32::NAN));
    assert!(matches!(
        out.event,
        Some(Event::Fault(Fault::Sensor { .. }))
    ));
    assert_descends(&mut c, out, sent);

    // A measured stretch where B has gone slack (λ = 3.9: λB = 0.1): a limit.
    let mut c = start(Settings::for_target(44.0)).unwrap();
    c.tick(Inputs::NONE);
    let sent = c.last_volts();
    let out = c.tick(Inputs::stretch(3.9));
    assert!(
        matches!(out.event, Some(Event::Fault(Fault::Limit { .. }))),
        "{out:?}"
    );
    assert_descends(&mut c, out, sent);

    // A stuck sensor: the same sample `stuck_samples` times in a row.
    let mut c = start(Settings::for_target(44.0)).unwrap();
    for _ in 1..100 {
        assert_eq!(c.tick(Inputs::stretch(2.0)).event, None);
    }
    let sent = c.last_volts();
    let out = c.tick(Inputs::stretch(2.0));
    assert!(
        matches!(
            out.event,
            Some(Event::Fault(Fault::SensorStuck { samples: 100, .. }))
        ),
        "{out:?}"
    );
    assert_descends(&mut c, out, sent);

    // An amplifier that follows its command is fine; one stuck below it (saturated at 3 kV)
    // is a fault once it has been off for more than AMPLIFIER_TICKS ticks.
    let mut c = start(Settings::for_target(44.0)).unwrap();
    let mut last = 0.0f32;
    let mut faulted_at = None;
    for k in 0..1000u32 {
        let monitored = last.min(3000.0);
        let out = c.tick(Inputs {
            amplifier_volts: Some(monitored),
            ..Inputs::NONE
        });
        if let Some(Event::Fault(fault)) = out.event {
            assert!(
                matches!(fault, Fault::AmplifierDisagrees { .. }),
                "{fault:?}"
            );
            faulted_at = Some((k, last));
            assert_descends(&mut c, out, last);
            break;
        }
        last = out.volts;
    }
    let (k, commanded) = faulted_at.expect("a saturated amplifier must be a fault");
    // At 10 V a tick the command passes 3200 V at tick 320; 3 ticks of grace after that.
    assert!(commanded > 3200.0 && k <= 325, "tick {k}, {commanded} V");

    // The IO side reports a bus error: it cannot ramp, 0 V at once; and a dead bus during
    // another fault's descent ends it at once too.
    let mut c = start(Settings::for_target(44.0)).unwrap();
    c.tick(Inputs::NONE);
    let out = c.fault(Fault::Bus);
    assert_eq!(
        (out.code, out.event),
        (DacCode(0), Some(Event::Fault(Fault::Bus)))
    );
    assert_eq!(c.tick(Inputs::NONE).code, DacCode(0));
    let mut c = start(Settings::for_target(44.0)).unwrap();
    for _ in 0..50 {
        c.tick(Inputs::NONE);
    }
    let out = c.tick(Inputs::stretch(f32::NAN));
    assert!(out.volts > 400.0, "{out:?}");
    let out = c.fault(Fault::Bus);
    assert_eq!((out.code, out.event), (DacCode(0), None));
    assert_eq!(
        c.latched_fault().map(|f| f.stage()),
        Some(FaultStage::Running)
    );
    assert!(matches!(c.latched_fault(), Some(Fault::Sensor { .. })));
    assert_eq!(c.tick(Inputs::NONE).code, DacCode(0));
}

/// Issue 12.2. A stretch sample no device can give (the bars more than a frame's length
/// outside the frame: the reference device's frame holds λ up to L1·λ1p/L1A = 4) is a
/// sensor fault; one past the far end but within reach of a sensor's noise (λB ≤ 0) is loss
/// of tension 1. Both give 0 V at once.
#[test]
fn samples_outside_the_model_or_any_device_are_refused() {
    for (sample, implausible) in [
        (1e6f32, true),
        (8.0, true),
        (-4.0, true),
        (f32::MAX, true),
        (4.0, false),
        (4.5, false),
        (-0.5, false),
        (0.0, false),
    ] {
        let mut c = start(Settings::for_target(44.0)).unwrap();
        c.tick(Inputs::NONE);
        let out = c.tick(Inputs::stretch(sample));
        assert_eq!(out.code, DacCode(0), "{sample}");
        match out.event {
            Some(Event::Fault(Fault::SensorImplausible { value, low, high })) => {
                assert!(implausible, "{sample}");
                assert_eq!((value, low, high), (sample, -4.0, 8.0));
            }
            Some(Event::Fault(Fault::Limit { mode, .. })) => {
                assert!(!implausible, "{sample}");
                assert_eq!(mode, de_resonator::FailureMode::LossOfTension1, "{sample}");
            }
            other => panic!("{sample}: {other:?}"),
        }
        assert_eq!(c.phase(), Phase::Faulted);
    }
}

/// Any settings, target and corruption, however wrong: no panic; if the controller starts
/// (on every check, or on the table alone), no tick ever commands more than
/// (1 − margin)·limit, and the code gives the volts reported. Inputs are drawn mostly
/// plausible (nineteen in twenty each) so that most cases start a controller and its ticks
/// are checked: the count is asserted (over half) and printed. The self-sensing probe is on
/// in most cases, its current monitor reading anything from a plausible ring to nonsense.
#[test]
fn no_input_makes_the_controller_exceed_the_limit() {
    use proptest::test_runner::TestRunner;
    use std::cell::Cell;
    // Plausible: a target in the tunable range (43.0 .. 45.95 Hz) for margins up to 0.1, an
    // AC that the plan holds; one draw in twenty wild for each.
    let strategy = (
        prop_oneof![19 => 43.1f32..45.9, 1 => any::<f32>()],
        prop_oneof![19 => 0.0f32..0.1, 1 => any::<f32>()],
        prop_oneof![19 => 1000.0f32..1e6, 1 => any::<f32>()],
        prop_oneof![19 => 0.0f32..40.0, 1 => any::<f32>()],
        prop_oneof![19 => 5.0f32..30.0, 1 => any::<f32>()],
        prop_oneof![19 => Just(None), 1 => (68usize..580).prop_map(Some)],
        prop_oneof![4 => Just(None), 15 => (1.0f32..100.0).prop_map(Some), 1 => any::<f32>().prop_map(Some)],
        prop_oneof![19 => Just(500.0f32), 1 => any::<f32>()],
        prop_oneof![19 => 0.0f32..1e-3, 1 => any::<f32>()],
    );
    // About 70% of the draws start a controller (39 to 54 of 64 over 50 runs); 64 cases once
    // fell to half or fewer in CI. At 256 the asserted half is some ten deviations below.
    let cases = 256;
    let (started, ticks) = (Cell::new(0u32), Cell::new(0u32));
    let mut runner = TestRunner::new(ProptestConfig::with_cases(cases));
    let result = runner.run(
        &strategy,
        |(target, margin, slew, ac_volts, ac_hz, corrupt, probe_volts, probe_hz, amps)| {
            let mut bytes = reference_table();
            if let Some(at) = corrupt {
                bytes[at] ^= 0x04;
            }
            let settings = Settings {
                margin,
                slew_volts_per_second: slew,
                ac_volts,
                ac_hz,
                check_seconds: 0.2,
                // Without the feature asking for the probe is a setting fault: not drawn.
                probe_volts: probe_volts.filter(|_| cfg!(feature = "probe")),
                probe_hz,
                ..Settings::for_target(target)
            };
            let params = REFERENCE_DEVICE.cast::<f32>();
            // Every check, and the table alone (a firmware without the solver and the model).
            let all = Controller::start(params, &bytes, amplifier(), settings);
            let table_only = Controller::from_table(params, &bytes, amplifier(), settings);
            let any = all.is_ok();
            for (mut c, boot) in [all, table_only].into_iter().flatten() {
                prop_assert!(corrupt.is_none());
                prop_assert!(boot.max_volts <= (1.0 - margin) * 9854.74);
                for k in 0..2000 {
                    let out = c.tick(Inputs::current(amps * (k as f32 * 0.37).sin()));
                    prop_assert!(out.volts >= 0.0 && out.volts <= boot.max_volts);
                    prop_assert_eq!(out.volts, amplifier().volts(out.code));
                    ticks.set(ticks.get() + 1);
                }
            }
            started.set(started.get() + u32::from(any));
            Ok(())
        },
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    println!(
        "{} of {cases} cases started a controller; {} ticks checked",
        started.get(),
        ticks.get()
    );
    assert!(started.get() * 2 > cases, "{} of {cases}", started.get());
}

/// The leakage watch: at a steady bias the current is the leakage Φ/R (and noise that
/// averages out over the window). R below `leakage_floor_ohms` is a `Leakage` fault within
/// the hold plus a window; R above it, none over three windows; no floor, no watch.
#[test]
fn the_leakage_watch_measures_the_dc_current_against_the_voltage() {
    for (floor, ohms, faults) in [
        (Some(1e10f32), 5e9f32, true),
        (Some(1e10), 2e10, false),
        (None, 1e6, false),
    ] {
        let settings = Settings {
            leakage_floor_ohms: floor,
            ..Settings::for_target(44.0)
        };
        let mut c = start(settings).unwrap();
        let (mut volts, mut fault, mut at_bias) = (0.0f32, None, None);
        // A ±1 µA square "noise" that averages out over the window.
        for k in 0..5000u32 {
            let noise = if k % 2 == 0 { 1e-6 } else { -1e-6 };
            let out = c.tick(Inputs::current(volts / ohms + noise));
            match out.event {
                Some(Event::Fault(f)) => {
                    fault = Some((k, f));
                    break;
                }
                Some(Event::AtBias { .. }) => at_bias = Some(k),
                _ => {}
            }
            volts = out.volts;
        }
        match (faults, fault) {
            (
                true,
                Some((
                    k,
                    Fault::Leakage {
                        ohms: seen,
                        floor_ohms,
                    },
                )),
            ) => {
                assert!((seen / ohms - 1.0).abs() < 1e-3, "{seen}");
                assert_eq!(Some(floor_ohms), floor);
                // Held from the tick after the bias is reached: one window, 1 s at 1 kHz.
                assert_eq!(Some(k), at_bias.map(|a| a + 1000));
            }
            (false, None) => {}
            other => panic!("{floor:?} {ohms}: {other:?}"),
        }
    }
}

/// The reference device's controller at 44 Hz (no AC) holding its bias, a stretch of 2.2
/// read to there (held bit for bit: no stuck-sensor check), and its settings.
fn holding_at_44_hz() -> (Controller, Settings) {
    let settings = Settings {
        stuck_samples: None,
        ..Settings::for_target(44.0)
    };
    let mut c = start(settings).unwrap();
    for _ in 0..1_200 {
        c.tick(Inputs::stretch(2.2));
    }
    assert_eq!(c.phase(), Phase::Holding);
    (c, settings)
}

/// The monitor acts before a limit (issue 44): at the bias for 44 Hz, a stretch that falls
/// toward the frame step by step (the membrane swinging back) meets A's tension along 1,
/// s1(λ) − ε·(Φ/H)²·λ·λ2p² > 0 (model.md §6.3), which fails at λ_limit under the bias and
/// at λ_near > λ_limit under the bias raised by 1/(1 − margin): both found here from the
/// stress in SI (tests/common), not from the core. The first fault is `NearLimit`, at the
/// first sample past λ_near, with its figures, well before λ_limit; then the descent.
#[test]
fn the_monitor_takes_the_drive_off_within_the_margin_before_the_limit() {
    let (mut c, settings) = holding_at_44_hz();
    let p = REFERENCE_DEVICE;
    // The voltage the monitor checks under: the plan's (the DAC's code rounds it).
    let volts = f64::from(c.plan().bias_volts);
    // A's tension along 1 at λ under Φ, Pa; its root by bisection below the equilibrium.
    let tension = |l: f64, volts: f64| {
        common::s1(&p, l, p.prestretch_2)
            - common::permittivity(&p) * (volts / p.thickness).powi(2) * l * p.prestretch_2.powi(2)
    };
    let root = |volts: f64| {
        let (mut lo, mut hi) = (0.3, 2.0);
        assert!(tension(lo, volts) < 0.0 && tension(hi, volts) > 0.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if tension(mid, volts) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    };
    let margin = f64::from(settings.margin);
    let (near, limit) = (root(volts / (1.0 - margin)), root(volts));
    assert!(near > limit + 1e-3, "{near} {limit}");
    let step = 1e-4;
    let mut stretch = 2.0f64;
    let fault = loop {
        stretch -= step;
        let out = c.tick(Inputs::stretch(stretch as f32));
        if let Some(Event::Fault(fault)) = out.event {
            break fault;
        }
        assert!(
            stretch > near - step,
            "no fault at λ {stretch} past λ_near {near}"
        );
    };
    match fault {
        Fault::NearLimit {
            mode,
            stretch: seen,
            volts: at,
            ..
        } => {
            assert_eq!(mode, de_resonator::FailureMode::LossOfTension1);
            assert!(
                f64::from(seen) <= near && f64::from(seen) > near - 2.0 * step,
                "λ {seen}, λ_near {near}"
            );
            assert_eq!(f64::from(at), volts);
            assert!(fault.to_string().contains("near a limit"), "{fault}");
        }
        other => panic!("{other}"),
    }
    assert_eq!(fault.stage(), FaultStage::Running);
}

/// The monitor's margin on the checks no voltage enters (issue 44): B goes slack along 1
/// where s1(λB) = 0, λB = λ2p^(−1/2) for any Gent membrane (the stress's numerator), so at
/// λ_slack = (L1·λ1p − L1B·λ2p^(−1/2))/L1A; the equilibrium λ* at the bias from the statics in
/// SI (tests/common). A stretch rising from λ* faults `NearLimit` (loss of tension 1) at the
/// first sample past λ* + (1 − margin)·(λ_slack − λ*), not at λ_slack.
#[test]
fn the_monitor_takes_the_drive_off_before_the_passive_membrane_goes_slack() {
    let (mut c, settings) = holding_at_44_hz();
    let p = REFERENCE_DEVICE;
    let volts = f64::from(c.plan().bias_volts);
    // λ* by bisection on Φ²(λ) = Φ², rising on the loading branch here.
    let (mut lo, mut hi) = (p.prestretch_1, 3.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if common::bias_squared(&p, mid) < volts * volts {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let equilibrium = lo;
    let slack = (common::length_1(&p) * p.prestretch_1 - p.length_passive / p.prestretch_2.sqrt())
        / p.length_active;
    let margin = f64::from(settings.margin);
    let near = equilibrium + (1.0 - margin) * (slack - equilibrium);
    let step = 1e-4;
    let mut stretch = equilibrium;
    let fault = loop {
        stretch += step;
        if let Some(Event::Fault(fault)) = c.tick(Inputs::stretch(stretch as f32)).event {
            break fault;
        }
        assert!(stretch < near + step, "no fault at λ {stretch} past {near}");
    };
    match fault {
        Fault::NearLimit {
            mode,
            stretch: seen,
            ..
        } => {
            assert_eq!(mode, de_resonator::FailureMode::LossOfTension1);
            // Within the samples' step and f32's rounding of the band's end.
            assert!(
                (f64::from(seen) - near).abs() < 2.0 * step,
                "λ {seen}, expected past {near} (λ* {equilibrium}, λ_slack {slack})"
            );
            assert!(f64::from(seen) < slack - 0.01);
        }
        other => panic!("{other}"),
    }
}
