//! The sans-IO controller on the host, as the firmware runs it: the boot's checks, the plan,
//! the ticks, the faults and their way down, the trim, with every kind of bad input the
//! firmware must survive. The table is in `tests/table.rs`, the DAC and amplifier in
//! `tests/drive.rs`.

mod common;

use common::{amplifier, reference_table, start_reference as start};

use de_resonator::table::{self, Table, TableError};
#[cfg(feature = "trim")]
use de_resonator::DeviceParams;
use de_resonator::{
    Amplifier, CodeError, Controller, DacCode, Device, Event, Fault, FaultStage, Inputs, Output,
    Phase, Setting, Settings, Tuner, REFERENCE_DEVICE,
};
use proptest::prelude::*;

/// The published figure (issue 2): 44 Hz takes 7449.88 V on the reference device. The
/// controller's f32 solve and the table's interpolation both land there.
#[test]
fn boot_tunes_the_reference_device_to_44_hz() {
    let params = REFERENCE_DEVICE.cast::<f32>();
    let (_, boot) = Controller::start(
        params,
        &reference_table(),
        amplifier(),
        Settings::for_target(44.0),
    )
    .unwrap();
    assert!(
        (boot.bias_volts - 7449.88).abs() < 0.02,
        "{}",
        boot.bias_volts
    );
    assert!(
        (boot.table_volts - 7449.88).abs() < 0.5,
        "{}",
        boot.table_volts
    );
    let limit_volts = boot.limit.unwrap().at.volts;
    assert!((limit_volts - 9854.73).abs() < 0.05, "{limit_volts}");
    // The cap: (1 − margin)·(1 − F32_GUARD)·Φlimit, the guard keeping f32 below f64.
    assert!((boot.max_volts - 0.95 * (1.0 - 1e-5) * 9854.73).abs() < 0.05);
    // The slow ramp stays near the static branch: no swing past the equilibrium's stretch
    // (2.19319 at 44 Hz) by more than a little.
    let (low, high) = boot.plan_stretch.unwrap();
    assert!(low >= 2.0 - 1e-6 && high < 2.21, "{low} .. {high}");
}

/// The table-only stage (a firmware without the solver): the bias is the table's, and the
/// cap stays below (1 − margin)·limit of the f64 solve for the settings' margin, also when it
/// is larger than the table's. A target whose bias lies above that cap is refused.
#[test]
fn table_only_boot_stays_below_the_limit_for_any_margin() {
    let params = REFERENCE_DEVICE.cast::<f32>();
    let limit = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .limit()
        .at
        .volts;
    let table = reference_table();
    for margin in [0.0f32, 0.05, 0.1, 0.2] {
        let settings = Settings {
            margin,
            ..Settings::for_target(45.0)
        };
        let (c, boot) = Controller::from_table(params, &table, amplifier(), settings).unwrap();
        // The documented cap: the table's top scaled by min(1, (1 − m)/(1 − m_table)).
        let top = Table::parse(&table).unwrap().max_volts();
        assert_eq!(boot.max_volts, top * ((1.0 - margin) / 0.95).min(1.0));
        let cap = (1.0 - f64::from(margin)) * limit;
        assert!(
            f64::from(boot.max_volts) <= cap,
            "margin {margin}: {boot:?}"
        );
        assert!(boot.limit.is_none() && boot.plan_stretch.is_none());
        assert_eq!(boot.bias_volts, boot.table_volts);
        assert_eq!(c.plan().bias_volts, boot.table_volts);
    }
    // 43 Hz needs 8.8 kV or so, above 0.8 of the 9.85 kV limit.
    let f43 = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .tune(43.0, 0.0)
        .unwrap()
        .volts;
    assert!(f43 > 0.8 * limit);
    let settings = Settings {
        margin: 0.2,
        ..Settings::for_target(43.0)
    };
    let fault = Controller::from_table(params, &table, amplifier(), settings).unwrap_err();
    assert!(matches!(fault, Fault::AboveSafe { .. }), "{fault:?}");
}

/// The stages taken one by one give what `start` gives.
#[test]
fn stages_one_by_one_are_start() {
    let params = REFERENCE_DEVICE.cast::<f32>();
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let table = reference_table();
    let (all, boot_all) = Controller::start(params, &table, amplifier(), settings).unwrap();
    let (mut c, boot) = Controller::from_table(params, &table, amplifier(), settings).unwrap();
    let boot = c.cross_check(boot).unwrap();
    let boot = c.check_plan(boot).unwrap();
    assert_eq!(boot, boot_all);
    assert_eq!(c.plan(), all.plan());
    // In place, as the firmware boots: the same controller in the slot, over whatever the
    // slot held; a refusal leaves it empty, never the old controller nor a half-checked one.
    let mut slot = Some(c);
    let boot = Controller::start_in(&mut slot, params, &table, amplifier(), settings).unwrap();
    assert_eq!(boot, boot_all);
    assert_eq!(slot.as_ref().unwrap().plan(), all.plan());
    // A stage's refusal leaves the controller faulted at 0 V, whoever carries on with it:
    // here the table and the direct solve made to disagree.
    let strict = Settings {
        agreement: 1e-9,
        ..settings
    };
    let (mut c, boot) = Controller::from_table(params, &table, amplifier(), strict).unwrap();
    let fault = c.cross_check(boot);
    assert!(matches!(fault, Err(Fault::Disagree { .. })), "{fault:?}");
    assert_eq!(c.phase(), de_resonator::Phase::Faulted);
    assert!((0..100).all(|_| c.tick(Inputs::NONE).volts == 0.0));
    // Refused before the controller is built (a torn table, a target off the table) and
    // after (an amplifier that cannot reach the bias: the plan's stage).
    let small = Amplifier::new(2.5, 1000.0).unwrap();
    for (table, amplifier, settings) in [
        (&table[..table.len() - 1], amplifier(), settings),
        (&table[..], amplifier(), Settings::for_target(1e6)),
        (&table[..], small, settings),
    ] {
        let mut slot = Some(all.clone());
        let fault = Controller::start_in(&mut slot, params, table, amplifier, settings);
        assert!(fault.is_err() && slot.is_none(), "{fault:?}");
    }
}

#[test]
fn ticks_ramp_at_the_slew_rate_hold_then_drive_and_never_exceed_the_limit() {
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let mut c = start(settings).unwrap();
    let amp = amplifier();
    let per_tick = settings.slew_volts_per_second / settings.tick_hz;
    let max = 0.95 * 9854.73;
    let (mut previous, mut at_bias, mut drive_on) = (0.0f32, None, None);
    for k in 0..3000u32 {
        let out = c.tick(Inputs::NONE);
        assert_eq!(out.volts, amp.volts(out.code));
        assert!(
            out.volts >= 0.0 && out.volts <= max,
            "tick {k}: {}",
            out.volts
        );
        if at_bias.is_none() {
            assert!(out.volts - previous <= per_tick + 0.2, "tick {k}: slew");
        }
        match out.event {
            Some(Event::AtBias { .. }) => at_bias = Some(k),
            Some(Event::DriveOn) => drive_on = Some(k),
            Some(Event::Fault(f)) => panic!("fault at {k}: {f}"),
            Some(e @ (Event::Trimmed { .. } | Event::DriveOff | Event::AboveCeiling { .. })) => {
                panic!("no trim was asked for: {e:?}")
            }
            None => {}
        }
        previous = out.volts;
    }
    // 7449.88 V at 10 V a tick: at bias on tick 745 (7450 V ≥ 7449.88); the AC 250 ticks
    // (0.25 s) later.
    assert_eq!(at_bias, Some(745));
    assert_eq!(drive_on, Some(995));
    assert_eq!(c.phase(), Phase::Driving);
    // The AC swings ±100 V about the bias, at the code resolution (10000/65536 V).
    let swing: Vec<f32> = (0..100).map(|_| c.tick(Inputs::NONE).volts).collect();
    let hi = swing.iter().cloned().fold(f32::MIN, f32::max);
    let lo = swing.iter().cloned().fold(f32::MAX, f32::min);
    assert!(
        (hi - 7549.88).abs() < 0.5 && (lo - 7349.88).abs() < 0.5,
        "{lo} {hi}"
    );
}

/// The settings' one list: every key is the `Settings` field's name, found again by
/// `from_key`; `set` then `get` gives the value back; 0 turns off what can be off.
#[test]
fn every_setting_by_its_key() {
    let keys = [
        "target_hz",
        "margin",
        "slew_volts_per_second",
        "tick_hz",
        "settle_seconds",
        "ac_volts",
        "ac_hz",
        "check_seconds",
        "agreement",
        "amplifier_tolerance_volts",
        "stuck_samples",
        "trim_tolerance",
        "trim_window_seconds",
        "trim_pulse_volts",
        "trim_probe_fraction",
        "trim_every_seconds",
        "leakage_floor_ohms",
        "leakage_fall_per_second",
        "track_seconds",
        "probe_volts",
        "probe_hz",
    ];
    assert_eq!(Setting::ALL.map(Setting::key), keys);
    let mut s = Settings::for_target(44.0);
    for (k, setting) in Setting::ALL.into_iter().enumerate() {
        assert_eq!(Setting::from_key(setting.key()), Some(setting));
        let value = 3.0 + k as f32;
        s.set(setting, value);
        assert_eq!(s.get(setting), value, "{setting:?}");
    }
    assert_eq!(Setting::from_key("ac_vols"), None);
    assert_eq!(s.stuck_samples, Some(13));
    assert_eq!((s.target_hz, s.trim_every_seconds), (3.0, Some(18.0)));
    for off in [
        Setting::StuckSamples,
        Setting::TrimTolerance,
        Setting::TrimEverySeconds,
        Setting::LeakageFloorOhms,
    ] {
        s.set(off, 0.0);
        assert_eq!(s.get(off), 0.0);
    }
    assert_eq!(
        (
            s.stuck_samples,
            s.trim_tolerance,
            s.trim_every_seconds,
            s.leakage_floor_ohms
        ),
        (None, None, None, None)
    );
}

/// Each setting out of its range is refused by name, before anything is driven: NaN and
/// negative values everywhere, zero where it must be positive, the AC at Nyquist or above,
/// a margin of exactly 1 or below 0 (the trim window's length:
/// `a_trim_window_too_long_for_its_samples_is_refused_saying_why`).
#[test]
fn each_bad_setting_is_refused_by_name() {
    use de_resonator::tuning::TuneError;
    let base = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let positive = [
        Setting::TickHz,
        Setting::SlewVoltsPerSecond,
        Setting::Agreement,
        Setting::AmplifierToleranceVolts,
        Setting::TrimWindowSeconds,
        Setting::TrimProbeFraction,
    ];
    let non_negative = [
        Setting::SettleSeconds,
        Setting::AcVolts,
        Setting::AcHz,
        Setting::CheckSeconds,
        Setting::TrimPulseVolts,
    ];
    let mut cases: Vec<(Setting, f32)> = Vec::new();
    for setting in positive {
        cases.extend([(setting, 0.0), (setting, -1.0), (setting, f32::NAN)]);
    }
    for setting in non_negative {
        cases.extend([
            (setting, -1e-3),
            (setting, f32::NAN),
            (setting, f32::INFINITY),
        ]);
    }
    cases.extend([(Setting::AcHz, 500.0), (Setting::TrimProbeFraction, 1.01)]);
    for (setting, value) in cases {
        let mut s = base;
        s.set(setting, value);
        match start(s) {
            Err(Fault::Setting {
                setting: named,
                value: v,
            }) => {
                assert_eq!(named, setting, "{value}");
                assert_eq!(v.to_bits(), value.to_bits(), "{setting:?}");
            }
            other => panic!("{setting:?} = {value}: {other:?}"),
        }
    }
    for margin in [1.0f32, -0.1, f32::NAN] {
        let fault = start(Settings { margin, ..base }).unwrap_err();
        assert!(
            matches!(fault, Fault::Tune(TuneError::InvalidMargin { .. })),
            "{margin}: {fault}"
        );
    }
}

/// The AC drive is bias + ac·sin(2π·f·(k − k_on)/tick_hz) from the tick it starts, tick by
/// tick within one DAC code (10 kV/65536), for 400 ticks (16 periods at 40 Hz).
#[test]
fn the_ac_drive_is_the_sine_from_its_first_tick() {
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let mut c = start(settings).unwrap();
    let mut on = None;
    for k in 0..2000u32 {
        let out = c.tick(Inputs::NONE);
        if out.event == Some(Event::DriveOn) {
            on = Some(k);
        }
        if let Some(k_on) = on.filter(|&k_on| k < k_on + 400) {
            let bias = f64::from(c.plan().bias_volts);
            let t = f64::from(k - k_on) / 1000.0;
            let expected = bias + 100.0 * (std::f64::consts::TAU * 40.0 * t).sin();
            let code = 10_000.0 / 65_536.0;
            assert!(
                (f64::from(out.volts) - expected).abs() <= 1.01 * code,
                "tick {k}: {} vs {expected}",
                out.volts
            );
        }
    }
    assert!(on.is_some());
}

/// A plan too long is refused on the sum of its parts, ramp + hold + check (a hold of 7·10⁴ s
/// is 7·10⁷ ticks, past `MAX_PLAN_TICKS`, with no check at all), and the hold is named when
/// its ticks (settle × rate) outnumber the ramp's, even when settle + rate would not.
#[test]
fn a_plan_too_long_is_the_sum_of_its_parts() {
    let base = Settings::for_target(44.0);
    for settings in [
        Settings {
            settle_seconds: 7e4,
            check_seconds: 0.0,
            ..base
        },
        Settings {
            settle_seconds: 7e4,
            slew_volts_per_second: 7.45,
            ..base
        },
    ] {
        match start(settings).unwrap_err() {
            Fault::Setting { setting, .. } => assert_eq!(setting, Setting::SettleSeconds),
            other => panic!("{other}"),
        }
    }
    // Just under the limit, the plan is made (its model check left out here: 6·10⁷ ticks).
    let long = Settings {
        settle_seconds: 6e4,
        check_seconds: 0.0,
        ..base
    };
    let params = REFERENCE_DEVICE.cast::<f32>();
    let (_, boot) = Controller::from_table(params, &reference_table(), amplifier(), long).unwrap();
    // f32 spaces its values by 4 at 6·10⁷: the plan's ticks are that close.
    let ramp = (boot.bias_volts / 10.0).ceil() as u32;
    assert!(
        boot.plan_ticks.abs_diff(ramp + 60_000_000 + 1) <= 4,
        "{boot:?}"
    );
}

/// Without AC the controller holds the bias for good: no `DriveOn`, ever.
#[test]
fn without_ac_the_bias_holds() {
    let mut c = start(Settings::for_target(44.0)).unwrap();
    let events: Vec<Event> = (0..3000)
        .filter_map(|_| c.tick(Inputs::NONE).event)
        .collect();
    assert_eq!(events.len(), 1, "{events:?}");
    assert!(matches!(events[0], Event::AtBias { .. }));
    assert_eq!(c.phase(), Phase::Holding);
}

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

#[test]
fn bad_targets_and_settings_are_refused_before_anything_is_driven() {
    for target in [f32::NAN, f32::INFINITY, -44.0, 0.0, 50.0, 42.0] {
        let fault = start(Settings::for_target(target)).unwrap_err();
        assert!(
            matches!(
                fault,
                Fault::Table(TableError::OutOfRange { .. }) | Fault::Tune(_)
            ),
            "{target}: {fault}"
        );
    }
    let base = Settings::for_target(44.0);
    for settings in [
        Settings {
            tick_hz: f32::NAN,
            ..base
        },
        Settings {
            slew_volts_per_second: 0.0,
            ..base
        },
        Settings {
            slew_volts_per_second: 1e-3,
            ..base
        },
        Settings {
            agreement: -1.0,
            ..base
        },
        Settings {
            ac_hz: 600.0,
            ac_volts: 1.0,
            ..base
        },
        Settings {
            settle_seconds: f32::INFINITY,
            ..base
        },
    ] {
        let fault = start(settings).unwrap_err();
        assert!(matches!(fault, Fault::Setting { .. }), "{fault}");
    }
    // Settings that can be off are `None` when off; on, they must make sense.
    for (settings, setting) in [
        (
            Settings {
                stuck_samples: Some(0),
                ..base
            },
            Setting::StuckSamples,
        ),
        (
            Settings {
                trim_tolerance: Some(-1e-3),
                ..base
            },
            Setting::TrimTolerance,
        ),
        (
            Settings {
                trim_tolerance: Some(1e-3),
                trim_every_seconds: Some(0.0),
                ..base
            },
            // Without the trim built in, asking for it is the first thing wrong.
            if cfg!(feature = "trim") {
                Setting::TrimEverySeconds
            } else {
                Setting::TrimTolerance
            },
        ),
    ] {
        match start(settings).unwrap_err() {
            Fault::Setting { setting: named, .. } => assert_eq!(named, setting),
            other => panic!("{setting:?}: {other}"),
        }
    }
    // A plan too long (beyond MAX_PLAN_TICKS) names the part that makes it so.
    for (settings, setting) in [
        (
            Settings {
                slew_volts_per_second: 1e-3,
                ..base
            },
            Setting::SlewVoltsPerSecond,
        ),
        (
            Settings {
                settle_seconds: 1e6,
                ..base
            },
            Setting::SettleSeconds,
        ),
        (
            Settings {
                check_seconds: 1e6,
                ..base
            },
            Setting::CheckSeconds,
        ),
    ] {
        match start(settings).unwrap_err() {
            Fault::Setting { setting: named, .. } => assert_eq!(named, setting),
            other => panic!("{setting:?}: {other}"),
        }
    }
    // A tick rate far too slow for the device (the model cannot step it stably, even in
    // substeps): named as the tick rate, not as a failed plan.
    let fault = start(Settings {
        tick_hz: 1e-6,
        ..base
    })
    .unwrap_err();
    assert_eq!(
        fault,
        Fault::Setting {
            setting: Setting::TickHz,
            value: 1e-6
        }
    );
    // The AC would take the peak past (1 − margin)·limit: a setting fault naming the AC.
    let fault = start(Settings {
        ac_volts: 2000.0,
        ac_hz: 40.0,
        ..base
    })
    .unwrap_err();
    assert_eq!(
        fault,
        Fault::Setting {
            setting: Setting::AcVolts,
            value: 2000.0
        }
    );
    // An amplifier that cannot reach the bias.
    let params = REFERENCE_DEVICE.cast::<f32>();
    let small = Amplifier::new(2.5, 1000.0).unwrap();
    let fault = Controller::start(params, &reference_table(), small, base).unwrap_err();
    assert!(
        matches!(fault, Fault::Amplifier(CodeError::OutOfRange { .. })),
        "{fault}"
    );
    // Parameters that are not safe at zero bias (B slack: λ1p below its slack stretch).
    let slack = de_resonator::DeviceParams {
        prestretch_1: 0.6,
        ..params
    };
    let fault = Controller::start(slack, &reference_table(), amplifier(), base).unwrap_err();
    assert!(matches!(fault, Fault::Device(_)), "{fault}");
}

/// An AC drive at the natural frequency, statically safe (peak below the safe maximum) but
/// undamped: the swing grows every period until it crosses a limit. The model run of the
/// plan finds it, and the controller refuses; the same AC off resonance is accepted.
#[test]
fn a_plan_that_crosses_dynamically_is_refused_by_the_model_check() {
    let off = Settings {
        ac_volts: 1800.0,
        ac_hz: 20.0,
        ..Settings::for_target(44.0)
    };
    let accepted = start(off);
    assert!(accepted.is_ok(), "{:?}", accepted.err());
    let resonant = Settings { ac_hz: 44.0, ..off };
    let fault = start(resonant).unwrap_err();
    // The crossing comes while the AC drives: after the ramp (745 ticks) and the hold (250),
    // within the 0.5 s the model follows the AC.
    match fault {
        Fault::PlanCrosses { seconds, .. } => {
            assert!(seconds > 0.995 && seconds <= 1.495, "{seconds}")
        }
        other => panic!("{other}"),
    }
}

/// Issue 12.1. A plant 20% stiffer than the device flashed (the core's f64 model of the
/// plant's own parameters, Q = 200, its stretch the sensor), and a target it reaches only
/// above the flashed device's ceiling. The trim measures the stiffer plant and says what it
/// would need (the plant's own bias for the target, by the f64 solve, plus the AC); no tick
/// ever commands more than (1 − margin)·Φlimit of the device flashed; the bias holds.
#[cfg(feature = "trim")]
#[test]
fn a_trim_on_a_stiffer_plant_never_lifts_the_ceiling() {
    let nominal = common::wide_range_device();
    let mut plant = DeviceParams {
        shear_modulus: 1.2 * nominal.shear_modulus,
        ..nominal
    };
    let plant_tuner = Tuner::new(Device::new(plant).unwrap());
    let f0 = plant_tuner.zero_bias().natural_frequency_hz;
    plant.damping = plant.effective_mass() * std::f64::consts::TAU * f0 / 200.0;
    let ceiling = 0.95 * Tuner::new(Device::new(nominal).unwrap()).limit().at.volts;
    let needed = plant_tuner.tune(32.5, 0.05).unwrap().volts + 100.0;
    assert!(needed > ceiling);

    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 29.0,
        trim_tolerance: Some(1e-3),
        ..Settings::for_target(32.5)
    };
    let table = common::made_table(nominal, 0.05, 64);
    let (mut c, _) = Controller::start(nominal.cast(), &table, amplifier(), settings).unwrap();
    let (events, highest) = against_plant(&mut c, plant, 4000);
    assert!(f64::from(highest) <= ceiling, "{highest} V");
    let held = events.iter().find_map(|&(_, e)| match e {
        Event::AboveCeiling {
            needed_volts,
            cap_volts,
        } => Some((needed_volts, cap_volts)),
        _ => None,
    });
    assert!(
        !events.iter().any(|(_, e)| matches!(e, Event::Fault(_))),
        "{events:?}"
    );
    let (asked, said_ceiling) = held.expect("the trim must say it needs more");
    assert!(
        (f64::from(asked) / needed - 1.0).abs() < 2e-3,
        "{asked} vs {needed}"
    );
    assert!(f64::from(said_ceiling) <= ceiling);
    assert_eq!(c.phase(), Phase::Held);
    assert_eq!(c.held_needing_volts(), Some(asked));

    // A target the stiffer plant reaches under the ceiling (33 Hz: 7525 V in the plant, plus
    // the AC): the trim converges and the AC starts; nothing holds.
    let reachable = Settings {
        target_hz: 33.0,
        ..settings
    };
    let (mut c, _) = Controller::start(nominal.cast(), &table, amplifier(), reachable).unwrap();
    let (events, highest) = against_plant(&mut c, plant, 4000);
    assert!(f64::from(highest) <= ceiling);
    assert!(
        events.iter().any(|(_, e)| *e == Event::DriveOn),
        "{events:?}"
    );
    assert!(
        !events
            .iter()
            .any(|(_, e)| matches!(e, Event::AboveCeiling { .. } | Event::Fault(_))),
        "{events:?}"
    );
    assert!(c.max_volts() <= c.ceiling_volts());
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

/// The controller against a plant: the core's f64 RK4 model of `plant` (its stretch the
/// sensor), one step a tick, the trim's job solved between ticks. What it said, when, and the
/// highest voltage it commanded.
#[cfg(feature = "trim")]
fn against_plant(
    c: &mut Controller,
    plant: DeviceParams<f64>,
    ticks: u32,
) -> (Vec<(u32, Event)>, f32) {
    let (said, volts, _) = timeline(c, plant, ticks);
    let highest = volts.iter().copied().fold(0.0f32, f32::max);
    (said, highest)
}

/// As `against_plant`, with every tick's voltage and how many trim jobs were handed out.
#[cfg(feature = "trim")]
fn timeline(
    c: &mut Controller,
    plant: DeviceParams<f64>,
    ticks: u32,
) -> (Vec<(u32, Event)>, Vec<f32>, u32) {
    use de_resonator::{Drive, Integrator, Method, State};
    let device = Device::new(plant).unwrap();
    let rest = State {
        stretch: plant.prestretch_1,
        velocity: 0.0,
    };
    let drive = |volts: f32| Drive::constant(&device, f64::from(volts));
    let range = device.model_range();
    let mut model =
        Integrator::new(device, drive(0.0), Method::Rk4, 1e-3, range, rest, true).unwrap();
    let (mut said, mut volts, mut jobs) = (Vec::new(), Vec::new(), 0);
    for k in 0..ticks {
        assert_eq!(c.ticks(), k);
        let out = c.tick(Inputs::stretch(model.state().stretch as f32));
        volts.push(out.volts);
        if let Some(event) = out.event {
            said.push((k, event));
        }
        if let Some(job) = c.trim_job() {
            jobs += 1;
            // Handed out once: not again until the next window.
            assert!(c.trim_job().is_none());
            c.trim_done(job.solve());
        }
        model.set_drive(drive(out.volts)).unwrap();
        model.step().unwrap();
    }
    (said, volts, jobs)
}

/// The trim's probe: with the target's bias above `trim_probe_fraction` of the cap, the
/// first ramp stops at that fraction (a softer plant is safe there); below it, at the bias
/// itself, whose first measurement then converges at once on a plant that is the model (one
/// trim, its next bias its own, then the AC).
#[cfg(feature = "trim")]
#[test]
fn the_trim_probes_low_then_converges_at_once_where_the_model_is_right() {
    let mut p = REFERENCE_DEVICE;
    let trimmed = |target| Settings {
        trim_tolerance: Some(1e-3),
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(target)
    };
    let (c, boot) =
        Controller::start(p.cast(), &reference_table(), amplifier(), trimmed(44.0)).unwrap();
    assert!(boot.bias_volts > 0.5 * boot.max_volts);
    assert_eq!(c.plan().bias_volts, 0.5 * boot.max_volts);
    // 45.5 Hz takes about 2 kV, below the probe: measured at its bias, the model's plant.
    let (mut c, boot) =
        Controller::start(p.cast(), &reference_table(), amplifier(), trimmed(45.5)).unwrap();
    assert_eq!(c.plan().bias_volts, boot.bias_volts);
    let f0 = Tuner::new(Device::new(p).unwrap())
        .zero_bias()
        .natural_frequency_hz;
    p.damping = p.effective_mass() * std::f64::consts::TAU * f0 / 200.0;
    let (events, _) = against_plant(&mut c, p, 3000);
    let trims: Vec<_> = events
        .iter()
        .filter_map(|&(_, e)| match e {
            Event::Trimmed {
                bias_volts,
                next_bias_volts,
                ..
            } => Some((bias_volts, next_bias_volts)),
            _ => None,
        })
        .collect();
    assert_eq!(
        trims,
        vec![(boot.bias_volts, boot.bias_volts)],
        "{events:?}"
    );
    assert!(events.iter().any(|(_, e)| *e == Event::DriveOn));
}

/// The amplifier must give the AC's peak on the tuned bias, not only the probe's ramp: a
/// 7.5 kV amplifier cannot give 44 Hz's 7450 V plus 100 V of AC, with the trim's probe at
/// 4.7 kV or without it.
#[test]
fn the_amplifier_must_give_the_tuned_bias_and_its_ac() {
    let small = Amplifier::new(2.5, 3000.0).unwrap();
    let trims = if cfg!(feature = "trim") {
        vec![None, Some(1e-3)]
    } else {
        vec![None]
    };
    for trim in trims {
        let settings = Settings {
            trim_tolerance: trim,
            ac_volts: 100.0,
            ac_hz: 40.0,
            ..Settings::for_target(44.0)
        };
        let params = REFERENCE_DEVICE.cast::<f32>();
        let fault = Controller::start(params, &reference_table(), small, settings).unwrap_err();
        assert!(matches!(fault, Fault::Amplifier(_)), "{trim:?}: {fault}");
    }
}

/// `cross_check` drives the solve's bias and plans its ticks for it: with a coarse table (8
/// points) the table's bias is volts off, the solve's within f32 of the f64 one; at a slow
/// ramp (100 V/s) the plan's ticks are those of the solve's bias.
#[test]
fn the_cross_check_drives_the_solves_bias() {
    let device = Device::new(REFERENCE_DEVICE).unwrap();
    let tuner = Tuner::new(device);
    let top = tuner.max_bias(table::table_margin(0.05)).unwrap();
    let mut points = vec![(0.0f32, 0.0f32); 8];
    table::fill(&device, &top, &[], &mut points).unwrap();
    let mut coarse = vec![0u8; table::table_bytes(8)];
    table::write(&mut coarse, &REFERENCE_DEVICE.cast(), 0.05, 0.0, &points).unwrap();
    let settings = Settings {
        slew_volts_per_second: 100.0,
        agreement: 1e-3,
        ..Settings::for_target(44.0)
    };
    let params = REFERENCE_DEVICE.cast::<f32>();
    let (c, boot) = Controller::start(params, &coarse, amplifier(), settings).unwrap();
    let solved = tuner.tune(44.0, 0.05).unwrap().volts;
    assert!(
        (f64::from(boot.table_volts) - solved).abs() > 0.5,
        "{boot:?}"
    );
    assert!(
        (f64::from(boot.bias_volts) - solved).abs() < 0.01,
        "{boot:?}"
    );
    assert_eq!(c.plan().bias_volts, boot.bias_volts);
    // Ramp ticks at 0.1 V a tick, then 0.25 s of hold and 0.5 s of model check, plus one.
    let ramp = (boot.bias_volts / 100.0 * 1000.0).ceil() as u32;
    assert_eq!(boot.plan_ticks, ramp + 250 + 500 + 1);
}

/// Issue 12.3. An AC amplitude above the bias would command below 0 V (a target at f0 has
/// no bias at all; the amplifier is unipolar): refused before anything is driven, as a
/// setting fault naming the AC amplitude. The same AC on a bias that holds it is accepted.
#[test]
fn a_plan_below_zero_volts_is_a_setting_fault() {
    let f0 = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .zero_bias()
        .natural_frequency_hz as f32;
    // f − f0 ∝ Φ² near zero bias: 1e-4 Hz below f0 takes about 50 V here.
    for target in [f0, f0 - 1e-4] {
        let fault = start(Settings {
            ac_volts: 100.0,
            ac_hz: 40.0,
            ..Settings::for_target(target)
        })
        .unwrap_err();
        assert_eq!(
            fault,
            Fault::Setting {
                setting: Setting::AcVolts,
                value: 100.0
            },
            "{target} Hz"
        );
    }
    let accepted = start(Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(45.5)
    });
    assert!(accepted.is_ok(), "{:?}", accepted.err());
    // AC volts without a frequency would drive nothing: refused, naming the frequency.
    let fault = start(Settings {
        ac_volts: 100.0,
        ..Settings::for_target(44.0)
    })
    .unwrap_err();
    assert!(
        matches!(
            fault,
            Fault::Setting {
                setting: Setting::AcHz,
                ..
            }
        ),
        "{fault}"
    );
}

/// Issue 12.4. A controller margin above the table's boots on every stage: the table's top
/// is scaled down to it, top·(1 − m)/(1 − m_table), which lies below (1 − m)·Φlimit of the
/// f64 solve (the table keeps its headroom), and the bias is the solve's.
#[test]
fn a_larger_margin_than_the_tables_scales_its_top() {
    let limit = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .limit()
        .at
        .volts;
    let table = reference_table();
    let top = Table::parse(&table).unwrap().max_volts();
    for margin in [0.1f32, 0.2, 0.3] {
        let settings = Settings {
            margin,
            ..Settings::for_target(45.0)
        };
        let params = REFERENCE_DEVICE.cast::<f32>();
        let (c, boot) = Controller::start(params, &table, amplifier(), settings).unwrap();
        let scaled = top * (1.0 - margin) / 0.95;
        let cap = (1.0 - f64::from(margin)) * limit;
        assert!(f64::from(boot.max_volts) <= cap, "{margin}: {boot:?}");
        assert!(f64::from(c.ceiling_volts()) <= cap);
        assert!(scaled <= boot.max_volts, "{margin}: {scaled} {boot:?}");
        let solved = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
            .tune(45.0, f64::from(margin))
            .unwrap()
            .volts;
        assert!((f64::from(boot.bias_volts) / solved - 1.0).abs() < 1e-5);
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
    let cases = 64;
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

/// The trim's timeline, tick by tick, each time from the settings (1 kHz, 10 V a tick, 0.25 s
/// of hold, a 200 V pulse for half a period of the target, a 0.5 s window, re-trim every 1 s):
/// the ramp to the probe (half the cap), the hold, the pulse, the window, the result applied
/// the tick after the window, the ramp to the next bias from the last one, and the secant's
/// next bias from the two measurements before it. The plant is the wide-range device with
/// its permittivity 15% off, which no μ alone describes, so the secant steps are needed.
#[cfg(feature = "trim")]
#[test]
fn the_trim_keeps_its_timeline_and_its_secant() {
    let nominal = common::wide_range_device();
    let mut plant = DeviceParams {
        relative_permittivity: 1.15 * nominal.relative_permittivity,
        ..nominal
    };
    let f0 = Tuner::new(Device::new(plant).unwrap())
        .zero_bias()
        .natural_frequency_hz;
    plant.damping = plant.effective_mass() * std::f64::consts::TAU * f0 / 200.0;
    let (target, tolerance) = (29.5f32, 1e-3f32);
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 26.0,
        trim_tolerance: Some(tolerance),
        trim_every_seconds: Some(1.0),
        ..Settings::for_target(target)
    };
    let table = common::made_table(nominal, 0.05, 64);
    let (mut c, boot) = Controller::start(nominal.cast(), &table, amplifier(), settings).unwrap();
    let probe = 0.5 * boot.max_volts;
    assert_eq!(c.plan().bias_volts, probe);
    assert_eq!(c.max_volts(), boot.max_volts);
    let (said, volts, jobs) = timeline(&mut c, plant, 9000);
    let (hold, pulse, window) = (250, (0.5f32 * 1000.0 / target).round() as u32, 500);
    // A tick reports the voltage its DAC code gives: within one code (10 kV/65536).
    let near = |v: f32, expected: f32| (v - expected).abs() <= 10_000.0 / 65_536.0;

    // The first ramp: 10 V a tick from 0 V, at the probe on the first tick that reaches it.
    let at_bias = (probe / 10.0).ceil() as u32;
    assert_eq!(said[0], (at_bias, Event::AtBias { volts: probe }));
    // Hold, then the pulse: 200 V down for `pulse` ticks from the tick after the hold.
    let start = at_bias + hold;
    assert!(near(volts[start as usize], probe));
    for k in start + 1..=start + pulse {
        assert!(near(volts[k as usize], probe - 200.0), "tick {k}");
    }
    assert!(near(volts[(start + pulse + 1) as usize], probe));

    // Every measurement: `window` ticks after the pulse, applied the tick after.
    let mut from = start;
    let mut trims = Vec::new();
    let mut previous: Option<(f32, f32)> = None;
    let mut driving_since = None;
    for &(k, event) in &said[1..] {
        match event {
            Event::Trimmed {
                bias_volts,
                measured_hz,
                next_bias_volts,
                ..
            } => {
                assert_eq!(k, from + 1 + pulse + window, "{event:?}");
                trims.push(k);
                let converged = (measured_hz - target).abs() <= tolerance * target;
                if converged && previous.is_some() {
                    assert_eq!(next_bias_volts, bias_volts);
                }
                if let (false, Some((b0, f0))) = (converged, previous) {
                    // The secant in (Φ², f), at most 10% of the bias a step.
                    let (b2, p2) = (bias_volts * bias_volts, b0 * b0);
                    let next = (b2 + (target - measured_hz) * (b2 - p2) / (measured_hz - f0))
                        .sqrt()
                        .clamp(0.9 * bias_volts, 1.1 * bias_volts);
                    assert!(
                        (next_bias_volts / next - 1.0).abs() < 1e-5,
                        "{next} {event:?}"
                    );
                }
                previous = (!converged).then_some((bias_volts, measured_hz));
                if next_bias_volts != bias_volts {
                    // The ramp from the bias measured at, 10 V a tick, to the next.
                    let step = 10.0 * (next_bias_volts - bias_volts).signum();
                    for n in 0..5 {
                        let ramp = bias_volts + step * n as f32;
                        let expected = if step > 0.0 {
                            ramp.min(next_bias_volts)
                        } else {
                            ramp.max(next_bias_volts)
                        };
                        assert!(
                            near(volts[(k + 1 + n) as usize], expected),
                            "tick {k} + {n}"
                        );
                    }
                }
            }
            Event::AtBias { volts: v } => {
                let last = said.iter().rev().find(|&&(j, _)| j < k).unwrap();
                if let (j, Event::Trimmed { bias_volts, .. }) = *last {
                    let ramp = ((v - bias_volts).abs() / 10.0).ceil() as u32;
                    assert_eq!(k, j + 1 + ramp, "{event:?}");
                }
                from = k + hold;
            }
            Event::DriveOn => {
                let &(j, last) = said.iter().rev().find(|&&(j, _)| j < k).unwrap();
                assert!(matches!(last, Event::Trimmed { .. }) && k == j + 1);
                driving_since = Some(k);
            }
            Event::DriveOff => {
                // Re-trim every second of drive, holding the bias first.
                assert_eq!(Some(k), driving_since.map(|d| d + 1000));
                from = k + hold;
                previous = None;
            }
            other => panic!("tick {k}: {other:?}"),
        }
    }
    assert!(trims.len() >= 5 && jobs as usize == trims.len(), "{said:?}");
    assert!(said.iter().any(|(_, e)| *e == Event::DriveOff));
    assert!(c.max_volts() <= c.ceiling_volts());
    assert!(volts.iter().all(|&v| v <= c.ceiling_volts()));
}

/// The controller on the amplifier's current alone against `plant` (the core's model,
/// integrated by RK4 at the tick): the current over each tick is the change of the membrane's
/// charge C(λ)·Φ, C = ε·L1A·L2·λ²·λ2p²/H (paper eq. 1), written out here from the geometry,
/// plus white noise of `noise_amps` (a tick). `each` sees the controller, the charge and the
/// tick's output; the trim's jobs are solved as they come.
#[cfg(feature = "trim")]
fn run_on_the_charge(
    plant: DeviceParams<f64>,
    settings: Settings,
    ticks: usize,
    noise_amps: f64,
    mut each: impl FnMut(&Controller, f64, &de_resonator::Output),
) {
    use de_resonator::{Drive, Integrator, Method, State};
    let mut c = start(settings).unwrap();
    let capacitance = |stretch: f64| {
        8.8541878128e-12
            * plant.relative_permittivity
            * plant.length_active
            * plant.width
            * (stretch * plant.prestretch_2).powi(2)
            / plant.thickness
    };
    let device = Device::new(plant).unwrap();
    let rest = State {
        stretch: plant.prestretch_1,
        velocity: 0.0,
    };
    let drive = |volts: f32| Drive::constant(&device, f64::from(volts));
    let mut model = Integrator::new(
        device,
        drive(0.0),
        Method::Rk4,
        1e-3,
        device.model_range(),
        rest,
        true,
    )
    .unwrap();
    let mut rng = common::Rng(0x5eed);
    let (mut volts, mut last_charge) = (0.0f32, None);
    for _ in 0..ticks {
        let charge = capacitance(model.state().stretch) * f64::from(volts);
        let inputs = match last_charge {
            Some(q) => Inputs::current(((charge - q) / 1e-3 + noise_amps * rng.gaussian()) as f32),
            None => Inputs::NONE,
        };
        last_charge = Some(charge);
        let out = c.tick(inputs);
        each(&c, charge, &out);
        if let Some(job) = c.trim_job() {
            c.trim_done(job.solve());
        }
        volts = out.volts;
        model.set_drive(drive(volts)).unwrap();
        model.step().unwrap();
    }
}

/// Self-sensing (model.md §8): with no stretch sample, the trim times the ring in the
/// amplifier's current. The plant is the model with μ 2% above the device told (so 44.5 Hz
/// lies in both tunable ranges), Q = 200, the monitor's noise 0.1 µA a tick. The trim
/// converges as it does on the stretch: the plant's frequency at the final bias within 0.1%
/// of the target, μ estimated within 0.1% of the plant's.
#[cfg(feature = "trim")]
#[test]
fn the_trim_measures_the_ring_in_the_current() {
    let told = REFERENCE_DEVICE;
    let mut plant = DeviceParams {
        shear_modulus: 1.02 * told.shear_modulus,
        ..told
    };
    let f0 = Tuner::new(Device::new(plant).unwrap())
        .zero_bias()
        .natural_frequency_hz;
    plant.damping = plant.effective_mass() * std::f64::consts::TAU * f0 / 200.0;
    let settings = Settings {
        trim_tolerance: Some(1e-3),
        ..Settings::for_target(44.5)
    };
    let (mut estimates, mut bias) = (Vec::new(), 0.0);
    run_on_the_charge(plant, settings, 6000, 1e-7, |c, _, out| {
        if let Some(Event::Trimmed { shear_modulus, .. }) = out.event {
            estimates.push(shear_modulus);
        }
        assert!(
            !matches!(out.event, Some(Event::Fault(_))),
            "{:?}",
            out.event
        );
        bias = f64::from(c.plan().bias_volts);
    });
    let device = Device::new(plant).unwrap();
    let last = *estimates.last().expect("a trim");
    assert!(
        (f64::from(last) / plant.shear_modulus - 1.0).abs() < 1e-3,
        "{estimates:?}"
    );
    let at = device.stretch_for_bias(bias, 3.0).unwrap();
    let error = device.natural_frequency_hz(at) / 44.5 - 1.0;
    assert!(error.abs() < 1e-3, "{error} at {bias} V");
}

/// The ring the trim's pulse leaves in the charge, as `trim::ring_charge_gain` predicts it
/// from the statics, against the charge of the model integrated through the pulse (undamped,
/// noise-free, the plant as told): its first swing after the pulse within 5% (the prediction
/// is linear in the pulse). A slow ramp (1 kV/s), so that the ring its end leaves is a
/// hundredth of the pulse's.
#[cfg(feature = "trim")]
#[test]
fn the_ring_in_the_charge_is_the_one_the_statics_predict() {
    use de_resonator::trim::ring_charge_gain;
    let settings = Settings {
        trim_tolerance: Some(1e-3),
        slew_volts_per_second: 1000.0,
        ..Settings::for_target(44.0)
    };
    let pulse_ticks = (0.5f32 * 1000.0 / 44.0).round();
    let (mut charges, mut bias) = (Vec::new(), None);
    run_on_the_charge(REFERENCE_DEVICE, settings, 6000, 0.0, |c, charge, out| {
        // From the pulse's end (the voltage back at the bias, measuring) for two periods.
        let at_bias = (out.volts - c.plan().bias_volts).abs() < 1.0;
        if c.phase() == de_resonator::Phase::Measuring && at_bias {
            bias = Some(c.plan().bias_volts);
            charges.push(charge);
        }
    });
    let bias = bias.expect("a pulse");
    // (The first sample is the tick before the pulse; the second still holds the pulse's
    // voltage, Q = C·Φ of the tick before.)
    let first: Vec<f64> = charges.iter().copied().skip(2).take(46).collect();
    let swing = first.iter().copied().fold(f64::MIN, f64::max)
        - first.iter().copied().fold(f64::MAX, f64::min);
    let device = Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap();
    let limit = Tuner::new(device).limit().at.offset;
    let gain = ring_charge_gain(&device, limit, bias, pulse_ticks / 1000.0);
    let predicted = f64::from(gain * bias * bias * settings.trim_pulse_volts);
    assert!(
        (0.5 * swing / predicted - 1.0).abs() < 0.05,
        "{} C measured, {predicted} C predicted at {bias} V",
        0.5 * swing
    );
}

/// Before it pulses, the trim on the charge weighs the ring the pulse would leave against the
/// monitor's noise heard in the hold: far too noisy a monitor (30 µA a tick) is refused then,
/// saying so, before any pulse (the voltage never below the bias); a quiet one (0.1 µA)
/// pulses and trims.
#[cfg(feature = "trim")]
#[test]
fn a_ring_too_weak_to_time_is_refused_before_the_pulse() {
    use de_resonator::TrimError;
    let settings = Settings {
        trim_tolerance: Some(1e-3),
        ..Settings::for_target(44.0)
    };
    for (noise_amps, refused) in [(3e-5, true), (1e-7, false)] {
        let (mut fault, mut pulsed, mut trimmed) = (None, false, false);
        run_on_the_charge(REFERENCE_DEVICE, settings, 2500, noise_amps, |c, _, out| {
            let bias = c.plan().bias_volts;
            if fault.is_none() && bias > 0.0 && out.volts < bias - 1.0 {
                pulsed = pulsed || c.phase() == de_resonator::Phase::Measuring;
            }
            match out.event {
                Some(Event::Fault(f)) => fault = fault.or(Some(f)),
                Some(Event::Trimmed { .. }) => trimmed = true,
                _ => {}
            }
        });
        if refused {
            assert!(
                matches!(fault, Some(Fault::Trim(TrimError::Unresolvable { .. }))) && !pulsed,
                "{noise_amps}: {fault:?}, pulsed {pulsed}"
            );
            let said = fault.unwrap().to_string();
            assert!(said.contains("too weak to time"), "{said}");
        } else {
            assert!(
                fault.is_none() && pulsed && trimmed,
                "{noise_amps}: {fault:?}"
            );
        }
    }
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

/// At faster ticks the trim's window averages strides of ticks into its 512 samples: with
/// default settings (0.5 s window) the trim tunes at 1.5, 2, 3 and 4 kHz as at 1 kHz, on the model's
/// plant with μ 2% above the device told (Q 200): the plant's own frequency at the bias it
/// ends at (f64 statics, model.md §5) within the tolerance, 1e-3, of the target.
#[cfg(feature = "trim")]
#[test]
fn the_trim_tunes_at_faster_ticks_with_default_settings() {
    let told = REFERENCE_DEVICE;
    let plant = common::with_quality_factor(
        DeviceParams {
            shear_modulus: 1.02 * told.shear_modulus,
            ..told
        },
        200.0,
    );
    let target_hz = 44.5;
    // Strides of 1 (500 samples), 2 (375), 2 (500), 3 (500) and 4 (500).
    for tick_hz in [1000.0f32, 1500.0, 2000.0, 3000.0, 4000.0] {
        let settings = Settings {
            trim_tolerance: Some(1e-3),
            tick_hz,
            ..Settings::for_target(target_hz)
        };
        let mut c = start(settings).unwrap();
        let mut p = common::Plant::new(plant, f64::from(tick_hz));
        let mut converged = false;
        for k in 0..(8.0 * tick_hz) as u32 {
            let out = c.tick(Inputs::stretch(p.stretch() as f32));
            match out.event {
                Some(Event::Fault(fault)) => panic!("{tick_hz} Hz, tick {k}: {fault}"),
                Some(Event::Trimmed {
                    bias_volts,
                    next_bias_volts,
                    ..
                }) => converged = bias_volts == next_bias_volts,
                _ => {}
            }
            if let Some(job) = c.trim_job() {
                c.trim_done(job.solve());
            }
            p.step(out.volts);
        }
        assert!(converged, "{tick_hz} Hz: {:?}", c.phase());
        let f = common::natural_hz_at(&plant, c.plan().bias_volts);
        assert!(
            (f / f64::from(target_hz) - 1.0).abs() <= 1e-3,
            "{tick_hz} Hz: {f} Hz"
        );
    }
}

/// The window's limits, said: at least four target periods; at 1 kHz a 1 s window (averaged in strides of 2, 500 Hz, 11
/// samples a period at 44.5 Hz) is taken; a 2 s one (strides of 4, 5.6 samples a period, past
/// the 64 periods 512 samples hold at 8 a period) is refused, the message saying the limit.
#[cfg(feature = "trim")]
#[test]
fn a_trim_window_too_long_for_its_samples_is_refused_saying_why() {
    let with_window = |seconds: f32| Settings {
        trim_tolerance: Some(1e-3),
        trim_window_seconds: seconds,
        ..Settings::for_target(44.5)
    };
    assert!(start(with_window(1.0)).is_ok());
    // Four periods at least (MIN_CROSSINGS both ways, and one for the charge's high-pass):
    // 4/44.5 Hz = 89.9 ms.
    assert!(start(with_window(0.090)).is_ok());
    assert!(matches!(
        start(with_window(0.089)),
        Err(Fault::Setting {
            setting: Setting::TrimWindowSeconds,
            ..
        })
    ));
    let fault = start(with_window(2.0)).unwrap_err();
    assert_eq!(
        fault,
        Fault::Setting {
            setting: Setting::TrimWindowSeconds,
            value: 2.0
        }
    );
    assert!(
        fault.to_string().contains("8 samples per target period"),
        "{fault}"
    );
}
