//! The sans-IO controller on the host, its boot and its plan, as the firmware runs them: the
//! boot's stages and checks, the settings by key and their refusals, the ramp, the hold and
//! the AC drive. Its run-time watch and faults are in `controller_watch.rs`, its closed-loop
//! trim in `controller_trim.rs`; the table in `table.rs`, the DAC and amplifier in `drive.rs`.

mod common;

use common::{amplifier, reference_table, start_reference as start};

use de_resonator::acquire::InputNoise;
use de_resonator::table::{self, Table, TableError};
use de_resonator::{
    Amplifier, CodeError, Controller, Device, Event, Fault, Inputs, Phase, Setting, Settings,
    Tuner, REFERENCE_DEVICE,
};

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
    let boot = c.cross_check(boot, &table).unwrap();
    let boot = c.check_plan(boot).unwrap();
    assert_eq!(boot, boot_all);
    assert_eq!(c.plan(), all.plan());
    // In place, as the firmware boots: the same controller in the slot, over whatever the
    // slot held; a refusal leaves it empty, never the old controller nor a half-checked one.
    let mut slot = Some(c);
    let boot = Controller::start_in(
        &mut slot,
        params,
        &table,
        (amplifier(), InputNoise::UNDECLARED),
        settings,
    )
    .unwrap();
    assert_eq!(boot, boot_all);
    assert_eq!(slot.as_ref().unwrap().plan(), all.plan());
    // A stage's refusal leaves the controller faulted at 0 V, whoever carries on with it:
    // here the table and the direct solve made to disagree.
    let strict = Settings {
        agreement: 1e-9,
        ..settings
    };
    let (mut c, boot) = Controller::from_table(params, &table, amplifier(), strict).unwrap();
    let fault = c.cross_check(boot, &table);
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
        let fault = Controller::start_in(
            &mut slot,
            params,
            table,
            (amplifier, InputNoise::UNDECLARED),
            settings,
        );
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

/// docs/settings.md, the settings' reference, is what their declarations say (each one's
/// id, key, unit, default, rule and doc): written from them with `UPDATE_DOCS=1 cargo test
/// --test controller settings_reference`, and compared with them in every other run.
#[test]
fn the_settings_reference_is_the_declarations() {
    use std::fmt::Write;
    let mut doc = String::from(
        "# Settings\n\n\
         What the controller is asked to do, and how: each setting by its key, as `get`, `set` \
         and `help` on the command port, a scene's `[controller]` table, a settings file for \
         `host-sim image --settings` and the Python package take it. A saved blob and an image \
         keep each by its id, which never changes: a firmware update keeps every saved setting \
         it knows, and gives the ones added since their image's values, or their defaults, \
         saying which. 0 turns off a setting that can be off.\n\n\
         This file is written from the declarations in `src/controller/settings.rs` \
         (`tests/controller.rs` checks it).\n\n\
         | id | key | unit | default | rule | what |\n|---|---|---|---|---|---|\n",
    );
    for setting in Setting::ALL {
        let default = setting.default_value();
        let default = if default == 0.0 && setting.rule().contains("off") {
            "off".to_string()
        } else {
            format!("{default}")
        };
        let what: Vec<&str> = setting.doc().collect();
        let _ = writeln!(
            doc,
            "| {} | `{}` | {} | {} | {} | {} |",
            setting.id(),
            setting.key(),
            setting.unit(),
            default,
            setting.rule(),
            what.join(" ").replace('|', "\\|")
        );
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/settings.md");
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, &doc).unwrap();
    }
    let kept = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        kept == doc,
        "docs/settings.md is not what the declarations say: UPDATE_DOCS=1 cargo test --test \
         controller settings_reference writes it"
    );
}

/// The settings' one list: every key is the `Settings` field's name, found again by
/// `from_key`; its stable id (what a saved blob and an image keep it by) is its place in
/// this hand-written list, so two declarations swapped, or an id changed, fail here; `set`
/// then `get` gives the value back; 0 turns off what can be off.
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
        "amplifier_slew_volts_per_second",
        "amplifier_bandwidth_hz",
    ];
    assert_eq!(Setting::ALL.map(Setting::key), keys);
    for (id, key) in keys.iter().enumerate() {
        let setting = Setting::from_key(key).unwrap();
        assert_eq!(usize::from(setting.id()), id, "{key}");
        assert_eq!(Setting::from_id(id as u8), Some(setting));
    }
    assert_eq!(Setting::from_id(keys.len() as u8), None);
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

/// The amplifier's declared slew rate (issue 60): a drive steeper than it is refused at boot
/// with both figures — the AC's slope 2π·f·A (the derivative of A·sin(2π·f·t) at its zero
/// crossing), a tracked drive's at 1.2 times the frequency on the ramp's rate, the ramp
/// itself — and one within it boots. Not declared (the default), nothing is asked of it.
#[test]
fn a_drive_steeper_than_the_amplifier_is_refused_with_both_figures() {
    let base = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let slope = std::f64::consts::TAU * 40.0 * 100.0; // 25,132.7 V/s
    let steeper = |settings: Settings| match start(settings) {
        Err(Fault::Steeper {
            setting,
            volts_per_second,
            amplifier_volts_per_second,
        }) => {
            let fault = Fault::Steeper {
                setting,
                volts_per_second,
                amplifier_volts_per_second,
            };
            let words = fault.to_string();
            assert!(
                words.contains(&format!("{}", amplifier_volts_per_second))
                    && words.contains(setting.key()),
                "{words}"
            );
            (setting, f64::from(volts_per_second))
        }
        other => panic!("{other:?}"),
    };
    let (setting, v) = steeper(Settings {
        amplifier_slew_volts_per_second: Some(20_000.0),
        ..base
    });
    assert_eq!(setting, Setting::AcVolts);
    assert!((v / slope - 1.0).abs() < 1e-6, "{v} {slope}");
    assert!(start(Settings {
        amplifier_slew_volts_per_second: Some(1.001 * slope as f32),
        ..base
    })
    .is_ok());
    assert!(start(base).is_ok());
    // The bias ramp faster than the amplifier.
    let (setting, v) = steeper(Settings {
        amplifier_slew_volts_per_second: Some(30_000.0),
        slew_volts_per_second: 40_000.0,
        ..base
    });
    assert_eq!((setting, v), (Setting::SlewVoltsPerSecond, 40_000.0));
    // A tracked drive at 44 Hz may follow up to 1.2 × 44 Hz while the bias moves at 10 kV/s
    // (a build with tracking).
    if cfg!(feature = "track") {
        let tracked = Settings {
            ac_hz: 44.0,
            trim_tolerance: Some(1e-3),
            track_seconds: Some(0.2),
            amplifier_slew_volts_per_second: Some(30_000.0),
            ..base
        };
        let (setting, v) = steeper(tracked);
        let expected = std::f64::consts::TAU * 1.2 * 44.0 * 100.0 + 10_000.0;
        assert_eq!(setting, Setting::AcVolts);
        assert!((v / expected - 1.0).abs() < 1e-6, "{v} {expected}");
    }
    // A declared slew that is no number, or not positive, is a bad setting.
    for bad in [0.0, -1.0, f32::NAN] {
        let settings = Settings {
            amplifier_slew_volts_per_second: Some(bad),
            ..base
        };
        refused_as_bad(settings, Setting::AmplifierSlewVoltsPerSecond);
    }
}

/// The amplifier's declared bandwidth (issue 60): an output that would follow the drive
/// further off its command than `amplifier_tolerance_volts` allows (the watch would fault it
/// running) is refused at boot with both figures. Against a first-order amplifier simulated
/// from the AC's switch-on (100 V at 40 Hz, 20 periods, 20,000 steps a period or a time
/// constant, whichever is shorter): at bandwidths from 20 to 0.05 times the drive's
/// frequency, a tolerance just under the simulated worst is refused (the figure said at
/// least that, at most 7% above it), one 7% above it boots; a tracked drive's over the
/// frequencies it may run, its bias moving. The ramp's lag, slew/(2π·f_c), and a bandwidth
/// that is no number, likewise.
#[test]
fn a_drive_the_amplifier_cannot_follow_is_refused_with_both_figures() {
    let base = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        slew_volts_per_second: 1000.0,
        ..Settings::for_target(44.0)
    };
    let lags = |settings: Settings| match start(settings) {
        Err(Fault::AmplifierLags {
            setting,
            following_volts,
            tolerance_volts,
        }) => {
            let fault = Fault::AmplifierLags {
                setting,
                following_volts,
                tolerance_volts,
            };
            let words = fault.to_string();
            assert!(
                words.contains(&de_resonator::Decimal(tolerance_volts).to_string())
                    && words.contains(&de_resonator::Decimal(following_volts).to_string())
                    && words.contains(setting.key()),
                "{words}"
            );
            (setting, f64::from(following_volts))
        }
        other => panic!("{other:?}"),
    };
    for x in [0.05, 0.2, 0.5, 1.0, 2.0, 5.0, 20.0] {
        let bandwidth = 40.0 / x;
        let worst = simulated_following(100.0, 40.0, bandwidth);
        let told = Settings {
            amplifier_bandwidth_hz: Some(bandwidth as f32),
            ..base
        };
        let (setting, following) = lags(Settings {
            amplifier_tolerance_volts: (0.999 * worst) as f32,
            ..told
        });
        assert_eq!(setting, Setting::AcVolts, "{x}");
        assert!(
            following >= 0.999 * worst && following <= 1.07 * worst,
            "{x}: {following} against {worst} simulated"
        );
        let fits = start(Settings {
            amplifier_tolerance_volts: (1.07 * worst) as f32,
            ..told
        });
        assert!(fits.is_ok(), "{x}: {worst}: {:?}", fits.err());
    }
    // A tracked drive (a build with tracking) may run from 0.8 to 1.2 times the target,
    // its bias moving at the ramp's rate: the worst over that span, plus the ramp's lag
    // slew/(2π·f_c); behind 9 Hz the span's x, 3.9–5.9, holds the error's peak (x = 4.9).
    if cfg!(feature = "track") {
        for bandwidth in [9.0, 26.4] {
            let ramp = 1000.0 / (std::f64::consts::TAU * bandwidth);
            // Past the ramp's own lag, short of the AC's.
            let tracked = Settings {
                ac_hz: 44.0,
                trim_tolerance: Some(1e-3),
                track_seconds: Some(0.2),
                amplifier_bandwidth_hz: Some(bandwidth as f32),
                amplifier_tolerance_volts: (2.0 * ramp) as f32,
                ..base
            };
            let span = (0..=16).map(|k| 44.0 * (0.8 + 0.025 * f64::from(k)));
            let worst = span
                .map(|hz| simulated_following(100.0, hz, bandwidth))
                .fold(0.0, f64::max)
                + ramp;
            let (setting, following) = lags(tracked);
            assert_eq!(setting, Setting::AcVolts);
            assert!(
                following >= 0.999 * worst && following <= 1.07 * worst,
                "tracked behind {bandwidth} Hz: {following} against {worst} simulated"
            );
        }
    }
    // The ramp at 40 kV/s behind 200 Hz lags by 40,000/(2π·200) = 31.8 V.
    let (setting, following) = lags(Settings {
        slew_volts_per_second: 40_000.0,
        amplifier_bandwidth_hz: Some(200.0),
        amplifier_tolerance_volts: 30.0,
        ..base
    });
    let expected = 40_000.0 / (std::f64::consts::TAU * 200.0);
    assert_eq!(setting, Setting::SlewVoltsPerSecond);
    assert!((following / expected - 1.0).abs() < 1e-6, "{following}");
    for bad in [0.0, -1.0, f32::NAN] {
        let settings = Settings {
            amplifier_bandwidth_hz: Some(bad),
            ..base
        };
        refused_as_bad(settings, Setting::AmplifierBandwidthHz);
    }
}

/// The most a first-order amplifier of `bandwidth_hz` is off an AC of `volts` at `hz`
/// switched on from rest: simulated over 20 periods, 20,000 steps a period or a time
/// constant, whichever is shorter (exact over each step for the command at its end).
fn simulated_following(volts: f64, hz: f64, bandwidth_hz: f64) -> f64 {
    let tau = 1.0 / (std::f64::consts::TAU * bandwidth_hz);
    let dt = tau.min(1.0 / hz) / 20_000.0;
    let keep = (-dt / tau).exp();
    let (mut out, mut worst) = (0.0f64, 0.0f64);
    for k in 1..=(20.0 / hz / dt) as usize {
        let command = volts * (std::f64::consts::TAU * hz * k as f64 * dt).sin();
        out = command + (out - command) * keep;
        worst = worst.max((command - out).abs());
    }
    worst
}

/// `settings` refused at boot as a bad `setting`.
fn refused_as_bad(settings: Settings, setting: Setting) {
    let fault = start(settings);
    assert!(
        matches!(fault, Err(Fault::Setting { setting: s, .. }) if s == setting),
        "{setting:?}: {fault:?}"
    );
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
    // It says the span the AC would drive about the bias, and the cap that refused it.
    let Fault::Swing {
        setting: Setting::AcVolts,
        value: 2000.0,
        low_volts,
        high_volts,
        max_volts,
    } = fault
    else {
        panic!("{fault:?}")
    };
    assert!(high_volts > max_volts && (high_volts - low_volts - 4000.0).abs() < 0.01);
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
/// undamped: the swing grows every period until it crosses a limit. The swing's prediction
/// refuses it (no bound at the resonance, model.md §7); the model run of the plan alone
/// (the table's stage, then `check_plan`) finds the crossing too; the same AC off resonance
/// is accepted.
#[test]
fn a_plan_that_crosses_dynamically_is_refused_by_the_model_check() {
    let off = Settings {
        ac_volts: 1500.0,
        ac_hz: 20.0,
        ..Settings::for_target(44.0)
    };
    let accepted = start(off);
    assert!(accepted.is_ok(), "{:?}", accepted.err());
    let resonant = Settings { ac_hz: 44.0, ..off };
    match start(resonant).unwrap_err() {
        Fault::DriveSwing(e) => assert!(
            matches!(
                e,
                de_resonator::SwingError::Unbounded {
                    resonance: de_resonator::Resonance::Harmonic,
                    ..
                } | de_resonator::SwingError::Crosses {
                    resonance: Some(de_resonator::Resonance::Harmonic),
                    ..
                }
            ),
            "{e}"
        ),
        other => panic!("{other}"),
    }
    let (mut c, boot) = Controller::from_table(
        REFERENCE_DEVICE.cast(),
        &reference_table(),
        amplifier(),
        resonant,
    )
    .unwrap();
    let fault = c.check_plan(boot).unwrap_err();
    // The crossing comes while the AC drives: after the ramp (745 ticks) and the hold (250),
    // within the 0.5 s the model follows the AC.
    match fault {
        Fault::PlanCrosses { seconds, .. } => {
            assert!(seconds > 0.995 && seconds <= 1.495, "{seconds}")
        }
        other => panic!("{other}"),
    }
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
/// swing fault naming the AC amplitude. The same AC on a bias that holds it is accepted.
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
        // Below 0 V: the span's low end is the bias (≈ 0) less the 100 V of AC.
        assert!(
            matches!(
                fault,
                Fault::Swing {
                    setting: Setting::AcVolts,
                    value: 100.0,
                    low_volts,
                    ..
                } if low_volts < 0.0 && low_volts > -100.01
            ),
            "{target} Hz: {fault:?}"
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

/// A boot onto a ring (issue 44, found by the long fuzz run, seed 44): with a slew of 10³⁰
/// V/s, a fault's way down is a step and so is the next boot's ramp after `clear` (which
/// waits for 0 V, not for the membrane to come to rest); each rings the membrane by about
/// the step Δλ = λ* − λ1p, and the rings add past B's slack stretch (the plant crossed at
/// λ 1.3409). The boot counts the way down's ring with its own and refuses, naming the
/// limit; the same plan at a slew the membrane follows (10 kV/s) boots.
#[test]
fn a_boot_counts_the_ring_of_a_way_down_at_its_slew() {
    let params = de_resonator::DeviceParams {
        shear_modulus: 224037.8125,
        jlim: None,
        relative_permittivity: 7.09597110748291,
        density: 1294.0030517578125,
        breakdown_field: 188106896.0,
        thickness: 0.00016290080384351313,
        length_active: 0.03831096366047859,
        length_passive: 0.02856992371380329,
        width: 0.0820452868938446,
        bar_mass: 0.01557159423828125,
        prestretch_1: 1.1604571342468262,
        prestretch_2: 1.176698923110962,
        damping: 0.00048489374332988654,
    };
    let table = common::made_table(params, 0.0, 64);
    let settings = |slew: f32| Settings {
        margin: 0.036618683,
        slew_volts_per_second: slew,
        settle_seconds: 0.20029642,
        check_seconds: 0.088311195,
        ac_volts: 3.4572124,
        ac_hz: 16.244635,
        ..Settings::for_target(25.479729)
    };
    let boot = |slew: f32| Controller::start(params.cast(), &table, amplifier(), settings(slew));
    match boot(1e30) {
        Err(Fault::DriveSwing(de_resonator::SwingError::Crosses { mode, .. })) => {
            assert_eq!(mode, de_resonator::FailureMode::LossOfTension1)
        }
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("a boot onto the ring of an instant way down was taken"),
    }
    assert!(boot(10_000.0).is_ok(), "{:?}", boot(10_000.0).err());
}
