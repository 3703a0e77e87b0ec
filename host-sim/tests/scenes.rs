//! Scenes: the firmware's controller against the full plant simulator (issue 5's musts), and
//! the plant simulator against the core where they describe the same device.

use std::path::Path;

use de_resonator::acquire::{InputError, Stall};
use de_resonator::estimate::capacitance::PROBE_SIGMAS;
use de_resonator::{Device, DeviceParams, EventKind, FailureMode, Fault, Tuner, REFERENCE_DEVICE};
use host_sim::engine::closed_loop::{Run, Said};
use host_sim::engine::plant::{AmplifierModel, Leakage, Plant};
use host_sim::scene;

mod common;

fn run(file: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(file);
    let mut s = scene::load(&path).unwrap();
    s.run.history = false;
    s.run.run().unwrap()
}

/// docs/scenes.md's results table, the row of `file`, quotes each of `figures`: each test
/// below that runs a shipped scene checks what the row says of it, so a documented figure
/// that drifts fails here.
fn documents(file: &str, figures: &[String]) {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/scenes.md"))
            .unwrap();
    let row = doc
        .lines()
        .find(|l| l.starts_with(&format!("| `{file}` |")))
        .unwrap_or_else(|| panic!("docs/scenes.md has no row for {file}"));
    // A figure as its own word: "2 trims" is not found in "12 trims".
    // As a figure of its own: no digit, point or sign before it, no digit after it.
    let quoted = |figure: &str| {
        row.match_indices(figure).any(|(at, _)| {
            let before = row[..at]
                .chars()
                .next_back()
                .is_some_and(|c| c.is_ascii_digit() || c == '.' || c == '−' || c == '-');
            let after = row[at + figure.len()..]
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit());
            !before && !after
        })
    };
    for figure in figures {
        assert!(
            quoted(figure),
            "docs/scenes.md's row for {file} is `{row}`: the run gives {figure}"
        );
    }
}

/// A relative error as the table writes it: two significant figures, a minus sign (−).
fn error_words(error: f64) -> String {
    let text = format!("{error:.1e}");
    match text.strip_prefix('-') {
        Some(abs) => format!("−{abs}"),
        None => text,
    }
}

/// When the run's first fault came, as the table writes it ("at 3.098 s").
fn fault_at(r: &Run) -> String {
    let e = r
        .events
        .iter()
        .find(|e| e.what.starts_with("fault"))
        .unwrap_or_else(|| panic!("no fault: {:?}", r.events));
    format!("at {:.3} s", e.seconds)
}

/// How many trims the run made ("2 trims").
fn trims(r: &Run) -> String {
    let n = r
        .events
        .iter()
        .filter(|e| e.what.starts_with("trim"))
        .count();
    format!("{n} trims")
}

/// The μ the last trim estimated, kPa, and as it said it ("μ estimated 36.00 kPa").
fn estimated(r: &Run) -> (f64, String) {
    let last = r
        .events
        .iter()
        .rev()
        .find(|e| e.what.starts_with("trim"))
        .unwrap_or_else(|| panic!("no trim: {:?}", r.events));
    let kpa = last.what.split("estimated ").nth(1).unwrap_or("");
    let kpa = kpa.split(' ').next().unwrap_or("");
    let value = kpa
        .parse()
        .unwrap_or_else(|_| panic!("no estimate in {:?}", last.what));
    (value, format!("μ estimated {kpa}"))
}

/// An ideal amplifier: the plant is the core's model exactly.
fn elastic_reference() -> Plant {
    Plant {
        params: REFERENCE_DEVICE,
        branches: Vec::new(),
        amplifier: AmplifierModel {
            gain: 4000.0,
            bandwidth_hz: f64::INFINITY,
            slew_volts_per_second: f64::INFINITY,
            rail_volts: f64::INFINITY,
        },
        leakage: Leakage::NONE,
    }
}

/// The plant's own statics and §6 checks (written out again in SI units, with finite
/// differences for the stiffness and the Hessian) against the published figures of the
/// reference device: 44 Hz at 7449.88 V, the limit EMI at 9854.73 V.
#[test]
fn plant_statics_and_limit_match_the_published_figures() {
    let plant = elastic_reference();
    let rest = plant.at_rest();
    let at = plant.equilibrium(&rest, 7449.88).unwrap();
    let f = plant.natural_frequency_hz(&at, 7449.88);
    assert!((f - 44.0).abs() < 44.0 * 1e-6, "{f}");
    let zero = plant.natural_frequency_hz(&rest, 0.0);
    let core = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap()).zero_bias();
    assert!(
        (zero - core.natural_frequency_hz).abs() < 1e-6 * zero,
        "{zero}"
    );
    let (mode, volts) = plant.limit_volts(&rest, 1000.0).unwrap();
    assert_eq!(mode, FailureMode::Emi);
    assert!((volts - 9854.73).abs() < 0.01, "{volts}");
}

/// MODEL.md §6.3 in the plant: A short (λ = 0.8) and B taut, under a voltage that puts A's
/// tension along 1 just below zero (its value from the core's stress, independent of the
/// plant's code): loss of tension 1; at 0.95 of that voltage, safe. Past the far end
/// (λB < 0) loss of tension 1 too.
#[test]
fn plant_checks_the_active_membranes_tension_and_the_model_domain() {
    let plant = elastic_reference();
    let p = REFERENCE_DEVICE;
    let mut y = plant.at_rest();
    y[0] = 0.8;
    let m = de_resonator::model::material::Gent::with_jlim(120.0);
    let tension = p.shear_modulus * m.stress_1(0.8, 2.0);
    let eps = p.relative_permittivity * de_resonator::model::device::VACUUM_PERMITTIVITY;
    // ε(Φ/H)²·λ·λ2p² = s1(λ) at Φ0.
    let zero_volts = (tension / (eps * 0.8 * 4.0)).sqrt() * p.thickness;
    assert_eq!(
        plant.first_failure(&y, 1.01 * zero_volts),
        Some(FailureMode::LossOfTension1)
    );
    assert_eq!(plant.first_failure(&y, 0.95 * zero_volts), None);
    y[0] = 4.2;
    assert_eq!(
        plant.first_failure(&y, 0.0),
        Some(FailureMode::LossOfTension1)
    );
}

/// No mismatch: the controller's bias gives the target within 0.1% in the plant, and the
/// plant stays inside its safe region throughout.
#[test]
fn reference_scene_tunes_within_a_tenth_of_a_percent() {
    let r = run("reference.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    let error = (r.natural_frequency_hz - 44.0) / 44.0;
    assert!(error.abs() < 1e-3, "{error}");
    assert_eq!(r.plant_crossing, None);
    assert_eq!(r.ticks, 10_000);
    documents(
        "reference.toml",
        &[
            format!("{:.4} Hz", r.natural_frequency_hz),
            format!("error {}", error_words(error)),
        ],
    );
    // The bias stays below the plant's own limit by about the 5% margin or more.
    let (_, limit) = r.limit.unwrap();
    assert!(r.bias_volts <= 0.95 * limit);
}

/// Each fault: the controller reports it, the output ends at 0 V, nothing crosses a limit.
#[test]
fn fault_scenes_end_at_zero_volts_and_safe() {
    type IsKind = fn(&Fault) -> bool;
    let cases: [(&str, IsKind); 5] = [
        ("fault-sensor-stuck.toml", |f| {
            matches!(f, Fault::SensorStuck { .. })
        }),
        // Two stalls recovered from (1.5 s, 3.0 s), the third within 1 s of the last.
        ("fault-adc-stall.toml", |f| {
            *f == Fault::Input(InputError::Stalled {
                stall: Stall::Overrun,
                recovered: 2,
            })
        }),
        ("fault-amplifier-saturated.toml", |f| {
            matches!(f, Fault::AmplifierDisagrees { .. })
        }),
        ("fault-dac-bus.toml", |f| matches!(f, Fault::Bus)),
        ("fault-outside-batch.toml", |f| {
            matches!(f, Fault::OutsideBatch { .. })
        }),
    ];
    for (file, kind) in cases {
        let r = run(file);
        let fault = r.fault.unwrap_or_else(|| panic!("{file}: no fault"));
        assert!(kind(&fault), "{file}: {fault:?}");
        assert!(
            r.final_membrane_volts.abs() < 1.0,
            "{file}: {}",
            r.final_membrane_volts
        );
        assert_eq!(r.final_command_volts, 0.0, "{file}");
        assert_eq!(r.plant_crossing, None, "{file}");
        documents(file, &[fault_at(&r)]);
    }
}

/// The stalls the scene injects: the two recovered from (1.5 s, 12.0 s) leave the drive
/// running, nothing said between them; its only fault is the third stall's, in the tick of
/// 14.0 s, 2 s after the last.
#[test]
fn stalls_recovered_from_leave_the_drive_running_until_one_repeats() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fault-adc-stall.toml");
    let mut s = scene::load(&path).unwrap();
    s.run.history = true;
    let r = s.run.run().unwrap();
    let said: Vec<(f64, &str)> = (r.events.iter())
        .map(|e| (e.seconds, e.what.as_str()))
        .collect();
    let faults: Vec<f64> = (said.iter())
        .filter(|(_, what)| what.contains("fault"))
        .map(|&(t, _)| t)
        .collect();
    assert_eq!(faults.len(), 1, "{said:?}");
    assert!((faults[0] - 14.0).abs() <= 1e-3 + 1e-9, "{faults:?}");
    let between: Vec<_> = (said.iter())
        .filter(|(t, _)| *t > 1.0 && *t < 14.0)
        .collect();
    assert!(
        between.is_empty(),
        "the drive as it was across the stalls: {between:?}"
    );
    // Driving to the end of the recovered stretch: the voltage swung by the AC at 13 s.
    let at = |t: f64| {
        (r.history.iter())
            .find(|s| s.seconds >= t)
            .map(|s| s.membrane_volts)
    };
    assert!(at(13.0).is_some_and(|v| v > 7000.0), "{:?}", at(13.0));
}

/// ±20% μ mismatch: the trim measures the ring, re-estimates μ and retunes; the plant ends
/// within 0.5% of the target (the trim's own tolerance is 0.1%), never outside its true
/// safe region. The estimate lands on the plant's μ.
#[test]
fn mismatch_scenes_trim_within_half_a_percent() {
    for (file, target, mu) in [
        ("mismatch-soft.toml", 29.5, 0.8 * 45e3),
        ("mismatch-stiff.toml", 33.0, 1.2 * 45e3),
    ] {
        let r = run(file);
        assert!(r.refused.is_none() && r.fault.is_none(), "{file}: {r:?}");
        let error = (r.natural_frequency_hz - target) / target;
        assert!(error.abs() < 5e-3, "{file}: {error}");
        assert_eq!(r.plant_crossing, None, "{file}");
        let trimmed = r.events.iter().filter(|e| e.what.starts_with("trim"));
        assert!(trimmed.count() >= 2, "{file}: {:?}", r.events);
        let (kpa, said) = estimated(&r);
        assert!((kpa * 1e3 / mu - 1.0).abs() < 1e-3, "{file}: {said}");
        documents(
            file,
            &[trims(&r), format!("error {}", error_words(error)), said],
        );
    }
}

/// A plant 20% stiffer than the device flashed, asked for a target it reaches only above
/// that device's ceiling, (1 − m)·Φlimit: the trim says what it would need (the plant's own
/// bias for the target, by the f64 solve on the true parameters, plus the AC) and holds the
/// bias it has. No command ever goes above the ceiling; nothing faults; the plant is safe.
#[test]
fn a_stiffer_plant_never_lifts_the_ceiling() {
    let r = run("mismatch-stiff-ceiling.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    let nominal = DeviceParams {
        shear_modulus: 45e3,
        jlim: Some(120.0),
        prestretch_1: 1.5,
        prestretch_2: 3.0,
        length_passive: 0.06,
        ..REFERENCE_DEVICE
    };
    let ceiling = 0.95 * Tuner::new(Device::new(nominal).unwrap()).limit().at.volts;
    let plant = DeviceParams {
        shear_modulus: 1.2 * 45e3,
        ..nominal
    };
    let needed = Tuner::new(Device::new(plant).unwrap())
        .tune(32.5, 0.05)
        .unwrap()
        .volts
        + 100.0;
    assert!(needed > ceiling, "{needed} {ceiling}");
    let said = r
        .events
        .iter()
        .find(|e| e.what.starts_with("trim needs"))
        .unwrap_or_else(|| panic!("no hold: {:?}", r.events));
    let asked: f64 = said.what["trim needs ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((asked / needed - 1.0).abs() < 2e-3, "{asked} vs {needed}");
    assert!(r.bias_volts <= ceiling && r.max_command_volts <= ceiling);
    assert_eq!(r.plant_crossing, None);
}

/// The viscoelastic VHB plant: within 0.5% at the end of the run after trimming (again every
/// second, as it creeps), never outside its true safe region.
#[test]
fn viscoelastic_scene_trims_within_half_a_percent() {
    let r = run("viscoelastic-vhb.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    let error = (r.natural_frequency_hz - 47.0) / 47.0;
    assert!(error.abs() < 5e-3, "{error}");
    assert_eq!(r.plant_crossing, None);
    assert!(r.events.iter().any(|e| e.what.contains("paused")));
    documents(
        "viscoelastic-vhb.toml",
        &[trims(&r), format!("error {} at 10 s", error_words(error))],
    );
}

/// Resonance tracking (issue 15): the VHB plant creeps for 60 s (its 6.6 s and 61 s
/// branches relax under the bias); the drive, once on, is never paused, and from 8 s on
/// the true plant's natural frequency (its own statics, networks frozen as they are, every
/// 0.1 s) stays within 0.1% of the target, while the bias it needs falls by hundreds of
/// volts. The tracker's Q is the plant's order of magnitude (30 set, the branches add loss).
/// (From 5 s before issue 25: the bias now waits until the drive has settled on the
/// resonance it measures, and the error was 1.09e-3 at 5.0 s, under 1e-3 from 5.2 s. From
/// 5.5 s before issue 60's amplifier: the tracker read the phase against the command, and
/// the 1.35° of lag behind the scene's 2 kHz offset the loop's creep-following error by
/// about 4e-4 the other way; read against the output, 1.35e-3 from 5.5 s.)
#[test]
fn tracking_holds_a_creeping_plant_within_a_tenth_of_a_percent() {
    let r = run("tracking-vhb.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    assert_eq!(r.plant_crossing, None);
    assert!(!r.events.iter().any(|e| e.what.contains("paused")));
    let from = r.tracking.iter().filter(|t| t.seconds >= 8.0 - 1e-9);
    let mut worst: f64 = 0.0;
    for t in from {
        // The drive on at every sample from 5 s (never paused), the plant on target.
        assert!(t.drive_hz.is_finite(), "{t:?}");
        worst = worst.max((t.plant_hz / 47.0 - 1.0).abs());
    }
    assert!(worst < 1e-3, "{worst}");
    assert_eq!(r.tracking.last().map(|t| t.seconds.round()), Some(60.0));
    // The drift the tracking followed: the bias at 5 s against the end.
    let at5 = r.tracking.iter().find(|t| t.seconds >= 5.0).unwrap();
    let end = r.tracking.last().unwrap();
    assert!(at5.bias_volts - end.bias_volts > 200.0, "{at5:?} {end:?}");
    assert!(
        end.quality_factor > 10.0 && end.quality_factor < 30.0,
        "{end:?}"
    );
    let error = r.natural_frequency_hz / 47.0 - 1.0;
    documents(
        "tracking-vhb.toml",
        &[
            format!("error {} at 60 s", error_words(error)),
            format!("Q measured {:.1} at the end", end.quality_factor),
        ],
    );
}

/// The stiff plant (a 0.2 ms branch) integrates with Radau through the whole run, safely, in
/// every build.
#[test]
fn stiff_scene_runs_with_radau() {
    let r = run("stiff-relaxation.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    assert_eq!(r.ticks, 2000);
    assert_eq!(r.plant_crossing, None);
}

/// Self-sensing (issue 15's first must): no displacement sensor, the trim times the ring in
/// the amplifier's current (1 µA rms a sample at 10 kHz, averaged over 1 kHz ticks). With the
/// plant's μ 20% off either way the plant ends within 0.5% of the target, μ estimated within
/// 0.1% of the true value (as with the displacement sensor), and the true plant is never
/// outside its safe region.
#[test]
fn sensorless_scenes_trim_on_the_current_within_half_a_percent() {
    for (file, target, mu) in [
        ("sensorless-soft.toml", 29.5, 0.8 * 45e3),
        ("sensorless-stiff.toml", 33.0, 1.2 * 45e3),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(file);
        let s = scene::load(&path).unwrap();
        // Through the board's ADC: the current channel, no stretch channel.
        let [current, _, stretch] = s.run.analog.unwrap().front_end.channels;
        assert!(current.is_some() && stretch.is_none(), "{file}");
        let r = run(file);
        assert!(r.refused.is_none() && r.fault.is_none(), "{file}: {r:?}");
        let error = (r.natural_frequency_hz - target) / target;
        assert!(error.abs() < 5e-3, "{file}: {error}");
        assert_eq!(r.plant_crossing, None, "{file}");
        let (kpa, said) = estimated(&r);
        assert!((kpa * 1e3 / mu - 1.0).abs() < 1e-3, "{file}: {said}");
        documents(
            file,
            &[
                trims(&r),
                format!("error {}", error_words(error)),
                said,
                format!("λ from C in {} windows", r.sensed.len()),
            ],
        );
        // The stretch from C under the probe (a window every 0.1 s, but while the trim
        // measures): inside the interval the monitor checks, PROBE_SIGMAS standard errors
        // wide, in every window; within 0.5% of the plant's mean stretch once driving.
        assert!(r.sensed.len() >= 80, "{file}: {}", r.sensed.len());
        let drive_on = r
            .events
            .iter()
            .find(|e| e.what.starts_with("AC drive on"))
            .unwrap()
            .seconds;
        for w in &r.sensed {
            let error = w.stretch - w.plant_stretch;
            assert!(
                error.abs() <= f64::from(PROBE_SIGMAS) * w.sigma,
                "{file}: {w:?}"
            );
            if w.seconds > drive_on + 0.2 {
                assert!((error / w.plant_stretch).abs() < 5e-3, "{file}: {w:?}");
            }
        }
    }
}

/// Self-sensing on the creeping VHB plant (`sensorless-vhb`, the current monitor only, the
/// probe on): as `viscoelastic-vhb` with its displacement sensor, the plant ends within 1e-3
/// of 47 Hz, never outside its safe region; λ from C in every window within the interval the
/// monitor checks.
#[test]
fn sensorless_vhb_trims_a_creeping_plant_and_reads_its_stretch() {
    let file = "sensorless-vhb.toml";
    let r = run(file);
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    assert_eq!(r.plant_crossing, None);
    let error = (r.natural_frequency_hz - 47.0) / 47.0;
    assert!(error.abs() < 1e-3, "{error}");
    assert!(r.sensed.len() >= 40, "{}", r.sensed.len());
    for w in &r.sensed {
        let error = w.stretch - w.plant_stretch;
        assert!(error.abs() <= f64::from(PROBE_SIGMAS) * w.sigma, "{w:?}");
    }
    documents(
        file,
        &[
            trims(&r),
            format!("error {} at 10 s", error_words(error)),
            format!("λ from C in {} windows", r.sensed.len()),
        ],
    );
}

/// Where self-sensing stops: at 30 and 100 times the monitor's noise the ring is lost in it;
/// the controller then faults (down to 0 V) or still lands within 0.5%, never mistunes
/// silently, and the plant stays safe.
#[test]
fn too_much_current_noise_faults_safely() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/sensorless-soft.toml");
    for factor in [30.0, 100.0] {
        let mut s = scene::load(&path).unwrap();
        s.run.history = false;
        let analog = s.run.analog.as_mut().unwrap();
        analog.noise_codes *= factor;
        let r = s.run.run().unwrap();
        assert_eq!(r.plant_crossing, None, "×{factor}");
        let error = (r.natural_frequency_hz - 29.5) / 29.5;
        assert!(
            r.fault.is_some() || error.abs() < 5e-3,
            "×{factor}: {error}"
        );
        if r.fault.is_some() {
            assert!(r.final_membrane_volts.abs() < 1.0, "×{factor}");
        }
    }
}

/// The electrical port against Ohm's law: a plant held at a constant voltage, at rest, draws
/// Φ/R_leak through its leakage (the charge no longer changes).
#[test]
fn the_current_at_rest_is_the_leakage() {
    let plant = Plant {
        leakage: Leakage {
            ohms: 2e9,
            final_ohms: 2e9,
            ..Leakage::NONE
        },
        ..elastic_reference()
    };
    let rest = plant.at_rest();
    let at = plant.equilibrium(&rest, 5000.0).unwrap();
    let amps = plant.mean_current_amps((at[0], 5000.0), (at[0], 5000.0), 1e-3, 1.0);
    assert!((amps - 5000.0 / 2e9).abs() < 1e-12 * 2.5e-6, "{amps}");
    // Charging at rest: the charge C(λ)·Φ of a parallel-plate capacitor of the membrane's
    // current area and thickness (incompressible: h = H/(λ·λ2p)), ε E² energy aside.
    let (lambda, volts) = (at[0], 5000.0);
    let p = &plant.params;
    let area = p.length_active * lambda * p.width * p.prestretch_2;
    let thickness = p.thickness / (lambda * p.prestretch_2);
    let capacitance = 8.8541878128e-12 * p.relative_permittivity * area / thickness;
    let no_leak = Plant {
        leakage: Leakage::NONE,
        ..plant.clone()
    };
    let charging = no_leak.mean_current_amps((lambda, 0.0), (lambda, volts), 1e-3, 1.0);
    assert!(
        (charging - capacitance * volts / 1e-3).abs() < 1e-12 * charging,
        "{charging}"
    );
}

/// When the membrane came to 0 V for good (within 1 V), s.
fn zero_volts_from(r: &Run) -> f64 {
    r.history
        .iter()
        .rev()
        .take_while(|h| h.membrane_volts.abs() < 1.0)
        .last()
        .unwrap()
        .seconds
}

/// The leakage watch (issue 15): the leakage resistance falls geometrically from 1 TΩ to
/// 100 MΩ over 10 s, and the membrane breaks down below 300 MΩ under voltage, at
/// t_b = 10·ln(3e8/1e12)/ln(1e8/1e12) s. With the watch's floor at 10 GΩ the controller
/// faults (`Leakage`) and is at 0 V before t_b; without the watch the plant breaks down at t_b.
#[test]
fn the_leakage_watch_faults_before_breakdown() {
    let breakdown_at = 10.0 * (3e8f64 / 1e12).ln() / (1e8f64 / 1e12).ln();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/leakage-ramp.toml");
    let mut s = scene::load(&path).unwrap();
    s.run.history = true;
    let r = s.run.run().unwrap();
    assert!(
        matches!(r.fault, Some(Fault::Leakage { .. })),
        "{:?}",
        r.fault
    );
    assert_eq!(r.plant_crossing, None);
    let zero_from = zero_volts_from(&r);
    assert!(
        zero_from < breakdown_at,
        "0 V from {zero_from} s, breakdown at {breakdown_at} s"
    );
    let Some(Fault::Leakage { ohms, .. }) = r.fault else {
        unreachable!()
    };
    documents(
        "leakage-ramp.toml",
        &[
            format!("(at {breakdown_at:.2} s)"),
            format!(
                "`Leakage` ({:.2} GΩ) {}",
                f64::from(ohms) / 1e9,
                fault_at(&r)
            ),
        ],
    );
    // The watch off: the same plant breaks down at t_b (within a tick).
    let mut s = scene::load(&path).unwrap();
    s.run.history = false;
    s.run.settings.leakage_floor_ohms = None;
    let r = s.run.run().unwrap();
    let (mode, at) = r.plant_crossing.expect("breakdown");
    assert_eq!(mode, FailureMode::Breakdown);
    assert!(
        (at - breakdown_at).abs() <= 1.5e-3,
        "{at} vs {breakdown_at}"
    );
    documents(
        "leakage-ramp.toml",
        &[format!("the plant breaks down at {at:.3} s")],
    );
    // No floor, the rate of fall only (the resistance falls 10^0.4 = 2.5 times a second;
    // 1.5 per second of R_previous/R − 1 allowed would pass it, 0.5 not): a fault of its
    // own kind, and 0 V, before t_b.
    for (rate, faults) in [(0.5, true), (2.0, false)] {
        let mut s = scene::load(&path).unwrap();
        s.run.history = true;
        s.run.settings.leakage_floor_ohms = None;
        s.run.settings.leakage_fall_per_second = Some(rate);
        let r = s.run.run().unwrap();
        if !faults {
            assert!(r.fault.is_none(), "{:?}", r.fault);
            continue;
        }
        assert!(
            matches!(r.fault, Some(Fault::LeakageFalling { .. })),
            "{:?}",
            r.fault
        );
        assert_eq!(r.plant_crossing, None);
        let zero_from = zero_volts_from(&r);
        assert!(zero_from < breakdown_at, "{zero_from} vs {breakdown_at}");
    }
}

/// Faster ticks (issue 27): a scene per device class (the neo-Hookean reference, the Gent
/// device trimmed sensorless on the current, the creeping VHB plant trimmed on its sensor)
/// at 2 and 4 kHz ticks, the settings otherwise the scene's (the trim's window the default
/// 0.5 s, averaged into its 512 samples): the same outcome as at 1 kHz, within the bounds
/// the scenes' own tests set at 1 kHz.
#[test]
fn each_device_class_runs_at_faster_ticks_with_default_settings() {
    for (file, target, bound) in [
        ("reference.toml", 44.0, 1e-3),
        ("sensorless-stiff.toml", 33.0, 5e-3),
        ("viscoelastic-vhb.toml", 47.0, 5e-3),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(file);
        let text = std::fs::read_to_string(path).unwrap();
        assert!(!text.contains("tick_hz"), "{file} sets its own tick");
        for tick_hz in [2000, 4000] {
            // The ADC scans at 20 kHz: a whole number of scans a tick at both rates.
            let faster = text
                .replace(
                    "[controller]\n",
                    &format!("[controller]\ntick_hz = {tick_hz}.0\n"),
                )
                .replace("scan_hz = 10000.0", "scan_hz = 20000.0");
            let mut s = scene::parse(&faster).unwrap();
            assert_eq!(s.run.settings.tick_hz, tick_hz as f32);
            s.run.history = false;
            let r = s.run.run().unwrap();
            assert!(
                r.refused.is_none() && r.fault.is_none(),
                "{file} {tick_hz}: {r:?}"
            );
            let error = r.natural_frequency_hz / target - 1.0;
            assert!(error.abs() < bound, "{file} {tick_hz}: {error}");
            assert_eq!(r.plant_crossing, None, "{file} {tick_hz}");
        }
    }
}

/// Self-sensing on devices no scene uses (issue 27): random valid devices, the plant exactly
/// as told, each run twice, with a displacement sensor and without (the trim on the charge,
/// the current monitor's noise 0.3–30 µA rms a 10 kHz sample, λ from C under a 20 V probe).
/// With the
/// sensor each tunes within 1e-3; without, each either tunes within 1e-3 too or faults
/// saying the ring is too weak to time (`TrimError::Unresolvable`), at 0 V, with no other
/// fault and never a wrong frequency.
#[test]
fn sensorless_trim_tunes_every_device_it_can_resolve_and_says_so_where_it_cannot() {
    use de_resonator::TrimError;
    let mut u = common::Uniform(0x2027);
    let (mut tried, mut resolved, mut refused, mut sensor_missed) = (0, 0, 0, 0);
    while tried < 24 {
        let Some((params, f0, f1)) = common::tunable_device(&mut u, None, 1.3) else {
            continue;
        };
        // A range worth tuning in.
        if (f1 / f0 - 1.0).abs() < 2e-3 {
            continue;
        }
        tried += 1;
        let target = f0 + 0.5 * (f1 - f0);
        let noise_amps = 10f64.powf(u.draw(-6.5, -4.5));
        let device_lines = host_sim::device_file::text(&params);
        let scene = |sensing: &str, extra: &str| {
            format!(
                "name = \"random\"\nduration_seconds = 8.0\nseed = {tried}\n\n[device]\n\
                 {device_lines}\n[plant]\nquality_factor = 200.0\nleakage_ohms = 1e12\n\n\
                 [amplifier]\nbandwidth_hz = 2000.0\nslew_volts_per_second = 200000.0\n\n\
                 {sensing}\n[controller]\ntarget_hz = {target}\nac_volts = 20.0\n\
                 ac_hz = {ac}\ntrim_tolerance = 1e-3\n{extra}",
                ac = 0.9 * target
            )
        };
        let run = |text: String| {
            let mut s = scene::parse(&text).unwrap();
            s.run.history = false;
            s.run.run().unwrap()
        };
        let with_sensor = run(scene("[sensor]\nnoise = 1e-5\nresolution = 1e-6\n", ""));
        let error = |r: &Run| r.natural_frequency_hz / f64::from(target as f32) - 1.0;
        if !(with_sensor.fault.is_none() && error(&with_sensor).abs() < 1e-3) {
            // The sensor's own trim missed (a device stiffening steeply near its top: left
            // open, issue 27): no reference to hold the self-sensing to.
            println!(
                "sensor missed {target} Hz by {:e}: {params:?}",
                error(&with_sensor)
            );
            sensor_missed += 1;
            continue;
        }
        let sensorless = run(scene(
            &format!(
                "[current_monitor]\nnoise_amps = {noise_amps:e}\nsample_hz = 10000.0\n\
                 resolution_amps = 1e-7\n"
            ),
            "probe_volts = 20.0\nprobe_hz = 500.0\n",
        ));
        assert_eq!(sensorless.plant_crossing, None, "{params:?}");
        match sensorless.fault {
            None => {
                resolved += 1;
                assert!(
                    error(&sensorless).abs() < 1e-3,
                    "{params:?} at {target} Hz, {noise_amps:e} A, sensorless: {:e}",
                    error(&sensorless)
                );
            }
            Some(Fault::Trim(TrimError::Unresolvable { .. })) => {
                refused += 1;
                assert!(sensorless.final_membrane_volts.abs() < 1.0, "{params:?}");
            }
            Some(fault) => panic!("{params:?} at {target} Hz, {noise_amps:e} A: {fault}"),
        }
    }
    println!(
        "{resolved} resolved, {refused} refused as too weak to time, {sensor_missed} missed \
         with the sensor too"
    );
    assert!(
        sensor_missed * 8 <= tried,
        "{sensor_missed} of {tried} missed with the sensor"
    );
    // Both ways taken: the property is tested on each side of the bound.
    assert!(
        resolved > 0 && refused > 0,
        "{resolved} resolved, {refused} refused"
    );
}

/// Issue 27's Gent device (jlim 100, λ1p 4, λ2p 1; tunable over 53.52–54.01 Hz only, so its
/// ring in the charge is weak), the plant as told, sensorless at 1 µA, 53.8 Hz: on each seed
/// it tunes within 1e-3 or says the ring is too weak to time, at 0 V; never a wrong estimate
/// (before: four seeds of six faulted on a μ estimate 10% low, "target outside the tunable
/// range").
#[test]
fn the_gent_device_of_issue_27_tunes_or_says_why() {
    use de_resonator::TrimError;
    for seed in 1..=4 {
        let text = format!(
            "name = \"gent\"\nduration_seconds = 8.0\nseed = {seed}\n[device]\njlim = 100.0\n\
             prestretch_1 = 4.0\nprestretch_2 = 1.0\n[plant]\nquality_factor = 200.0\n\
             leakage_ohms = 1e12\n[amplifier]\nbandwidth_hz = 2000.0\n\
             slew_volts_per_second = 200000.0\n[current_monitor]\nnoise_amps = 1e-6\n\
             sample_hz = 10000.0\nresolution_amps = 1e-7\n[controller]\ntarget_hz = 53.8\n\
             ac_volts = 100.0\nac_hz = 50.0\ntrim_tolerance = 1e-3\nprobe_volts = 20.0\n\
             probe_hz = 500.0\n"
        );
        let mut s = scene::parse(&text).unwrap();
        s.run.history = false;
        let r = s.run.run().unwrap();
        assert_eq!(r.plant_crossing, None, "seed {seed}");
        match r.fault {
            None => {
                let error = r.natural_frequency_hz / f64::from(53.8f32) - 1.0;
                assert!(error.abs() < 1e-3, "seed {seed}: {error:e}");
            }
            Some(Fault::Trim(TrimError::Unresolvable { .. })) => {
                assert!(r.final_membrane_volts.abs() < 1.0, "seed {seed}");
            }
            Some(fault) => panic!("seed {seed}: {fault}"),
        }
    }
}

/// An operator mid-run (`operator-commands.toml`, issue 28): `target 45` at 3 s retunes the
/// drive, `stop` at 5 s brings it to 0 V with the output off, `clear` at 6 s re-arms with the
/// output still off, `start` at 6.5 s drives again with the settings in force. Each line is
/// answered `ok`; the plant is at rest between the stop's ramp and the start; at the end the
/// plant's own natural frequency (its separate statics) is 45 Hz within 1e-3, the plant safe
/// throughout.
#[test]
fn an_operator_retargets_stops_and_starts_mid_run() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/operator-commands.toml");
    let mut s = scene::load(&path).unwrap();
    s.run.history = true;
    let r = s.run.run().unwrap();
    let lines: Vec<&str> = r.commands.iter().map(|c| c.line.as_str()).collect();
    assert_eq!(lines, ["target 45", "stop", "clear", "start"]);
    for c in &r.commands {
        assert!(c.reply.starts_with("ok"), "{c:?}");
    }
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    assert_eq!(r.plant_crossing, None);
    assert_eq!(r.target_hz, 45.0);
    let error = r.natural_frequency_hz / 45.0 - 1.0;
    assert!(error.abs() < 1e-3, "{error}");
    documents(
        "operator-commands.toml",
        &[format!(
            "{:.4} Hz at the end, error {}",
            r.natural_frequency_hz,
            error_words(error)
        )],
    );
    // At rest (0 V, the output off) from the stop's ramp end until the start.
    let rested = r
        .events
        .iter()
        .find(|e| e.seconds > 5.0 && e.what.starts_with("at rest, 0 V"))
        .unwrap()
        .seconds;
    for h in r
        .history
        .iter()
        .filter(|h| h.seconds > rested + 0.05 && h.seconds < 6.5)
    {
        assert!(h.membrane_volts.abs() < 1.0 && !h.enable, "{h:?}");
    }
    documents(
        "operator-commands.toml",
        &[format!("from {rested:.3} s to the start")],
    );
    // Driven again after the start: the AC on once more.
    assert!(
        r.events
            .iter()
            .any(|e| e.seconds > 6.5 && e.what == "AC drive on"),
        "{:?}",
        r.events
    );
}

/// What a scene's `[[commands]]` and `[front_end]` may hold is checked before any work: no
/// `reset`, a time within the scene, one line; a front end the board could run, and not with
/// sensors read directly; a stuck stretch input only through a front end.
#[test]
fn scene_commands_and_front_ends_are_checked() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/operator-commands.toml"),
    )
    .unwrap();
    let cases = [
        (base.replace("line = \"stop\"", "line = \"reset\""), "reset"),
        (
            base.replace("at_seconds = 6.5", "at_seconds = 12.0"),
            "at_seconds",
        ),
        (
            base.replace("scan_hz = 10000.0", "scan_hz = 10500.0"),
            "scans",
        ),
        (
            base.replace("[front_end]\n", "[sensor]\nnoise = 1e-5\n\n[front_end]\n"),
            "[sensor]",
        ),
        (
            base.replace("noise_codes = 1.0", "noise_codes = -1.0"),
            "noise_codes",
        ),
        (
            format!("{base}\n[faults]\nstretch_stuck_after_seconds = -1.0\n"),
            "stretch_stuck_after_seconds",
        ),
    ];
    for (text, word) in cases {
        let err = scene::parse(&text).unwrap_err();
        assert!(err.contains(word), "{word}: {err}");
    }
    let direct = "name = \"direct\"\n[sensor]\nnoise = 1e-5\n[controller]\ntarget_hz = 44.0\n\
                  [faults]\nstretch_stuck_after_seconds = 1.0\n";
    let err = scene::parse(direct).unwrap_err();
    assert!(err.contains("[front_end]"), "{err}");
}

/// Issue 45's low pre-stretch device (λ1p = λ2p = 1.2, neo-Hookean) on a creeping plant (Q 40,
/// a 500 Pa branch relaxing over 6 s), the stretch read through the shipped scenes' ADC
/// channel (IN12, 5.4e-4 a count, 10 scans a 1 kHz tick), target 60 Hz, a tracked 60 V drive.
/// `noise_codes` (the ADC's noise, which the image declares too) and the stretch sensor
/// (`[sensor]`: the plant read directly) as given.
fn low_prestretch_scene(
    noise_codes: f64,
    sensor: Option<f64>,
    seconds: f64,
    damping: f64,
) -> String {
    let front_end = match sensor {
        Some(noise) => format!("[sensor]\nnoise = {noise:e}\n"),
        None => format!(
            "[front_end]\nscan_hz = 10000.0\nnoise_codes = {noise_codes}\n\
             [front_end.stretch]\ninput = 12\nzero_code = -1650.0\nper_count = 5.4054054e-4\n\
             low = 1.0\nhigh = 3.0\n"
        ),
    };
    format!(
        "name = \"low-prestretch\"\nduration_seconds = {seconds}\n\
         [device]\nprestretch_1 = 1.2\nprestretch_2 = 1.2\ndamping = {damping:e}\n\
         [plant]\nquality_factor = 40.0\n\
         branches = [{{ modulus = 500.0, relaxation_seconds = 6.0 }}]\n\
         [amplifier]\nbandwidth_hz = 2000.0\nslew_volts_per_second = 200000.0\n\
         {front_end}\
         [controller]\ntarget_hz = 60.0\nac_volts = 60.0\nac_hz = 60.0\n\
         trim_tolerance = 1e-3\ntrack_seconds = 1.0\n"
    )
}

/// Issue 45, the trim through the board's own stretch channel: the first trim's reading
/// (measured frequency and the resolution it claims), against the same window read through
/// an ideal sensor (1e-6 of noise: the peer). From 0.25 to 1 code of ADC noise each reading is
/// within four of the deviations its resolution claims (`TIMING_ERROR_TIMES_RESOLUTION`) of the
/// peer's (the code before measured 55–62 Hz here and asked for 22.5–35 kV); at 1.5 and 2
/// codes the ring is refused as too weak to time with its figures: before any voltage where
/// the device is told the plant's damping, in the window after the pulse (no reading adopted,
/// 0 V at the end) where it is told half of it. Over 20 s at 1 code the tracked drive (the low pre-stretch tunes slowly: 0.8%
/// of f takes 5.8 → 9.6 kV) brings the plant's own natural frequency (its separate statics)
/// within 1e-3 of the target.
#[test]
fn a_trim_through_the_stretch_channel_adopts_only_what_it_resolves() {
    use de_resonator::estimate::ring::TIMING_ERROR_TIMES_RESOLUTION;
    use de_resonator::{EventKind, TrimError};
    // The device told the plant's damping: c = M·ω/Q for Q 40 at 60 Hz, N·s.
    const TOLD: f64 = 5.6e-4;
    let run = |text: String| {
        let mut s = scene::parse(&text).unwrap();
        s.run.history = false;
        s.run.run().unwrap()
    };
    let first_trim = |r: &Run| {
        r.events
            .iter()
            .find(|e| e.kind == EventKind::Trimmed)
            .map(|e| (e.values[1].1, e.values[4].1))
    };
    let peer = run(low_prestretch_scene(0.0, Some(1e-6), 2.2, TOLD));
    let (peer_hz, _) = first_trim(&peer).expect("the ideal sensor's trim");
    for noise_codes in [0.25, 0.5, 1.0] {
        let r = run(low_prestretch_scene(noise_codes, None, 2.2, TOLD));
        assert_eq!(r.fault, None, "{noise_codes}");
        let (hz, resolution) = first_trim(&r).expect("a trim");
        let claimed = f64::from(TIMING_ERROR_TIMES_RESOLUTION) / resolution;
        let error = hz / peer_hz - 1.0;
        assert!(
            error.abs() <= 4.0 * claimed,
            "{noise_codes} codes: {hz} Hz against {peer_hz} Hz, resolution {resolution}"
        );
    }
    for noise_codes in [1.5, 2.0] {
        // Told the plant's damping, the boot refuses the ring before any voltage.
        let r = run(low_prestretch_scene(noise_codes, None, 2.2, TOLD));
        let refused = r.refused.clone().unwrap_or_default();
        assert!(
            refused.contains("ring in the stretch is too weak")
                && refused.contains("before any voltage"),
            "{noise_codes} codes: {refused}"
        );
        assert_eq!(r.max_command_volts, 0.0, "{noise_codes} codes");
        // Told half of it, the boot's prediction passes and the window refuses the ring.
        let r = run(low_prestretch_scene(noise_codes, None, 2.2, 0.5 * TOLD));
        assert!(
            matches!(r.fault, Some(Fault::Trim(TrimError::Unresolvable { .. }))),
            "{noise_codes} codes: {:?}",
            r.fault
        );
        assert_eq!(first_trim(&r), None, "{noise_codes} codes");
        let words = r.fault_words.clone().unwrap_or_default();
        assert!(words.contains("ring in the stretch is too weak"), "{words}");
        assert!(r.final_membrane_volts.abs() < 1.0, "{noise_codes} codes");
    }
    let r = run(low_prestretch_scene(1.0, None, 20.0, TOLD));
    assert_eq!((r.fault, r.plant_crossing), (None, None));
    let error = r.natural_frequency_hz / 60.0 - 1.0;
    assert!(error.abs() < 1e-3, "{error:e}");
}

/// Issue 45, refused up front: `sensorless-soft.toml` with its ADC 10 times noisier (20
/// codes, 10 µA a conversion), which the image declares: the first pulse's ring (from the
/// statics, the device's damping) against that noise cannot be timed to the tolerance, so
/// the boot refuses it with its figures and nothing is driven (the code before ramped to
/// 4 kV and faulted there). The same board declaring 2 codes (its maker measured less than it
/// has) ramps and times the first ring (at the probe's bias, strong enough) within what its
/// resolution claims of the shipped scene's reading (the peer, 2 codes), then refuses the
/// second (at the lower bias, weaker) as too weak to time from the noise it hears (in the
/// hold or, the undamped prediction passing there, in the window): no estimate from it.
#[test]
fn a_trim_the_image_says_cannot_resolve_is_refused_before_any_voltage() {
    use de_resonator::estimate::ring::TIMING_ERROR_TIMES_RESOLUTION;
    use de_resonator::{EventKind, TrimError};
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/sensorless-soft.toml"),
    )
    .unwrap();
    let noisy = text.replace("noise_codes = 2.0", "noise_codes = 20.0");
    assert_ne!(noisy, text);
    let run = |text: &str| {
        let mut s = scene::parse(text).unwrap();
        s.run.history = false;
        s.run.run().unwrap()
    };
    let r = run(&noisy);
    let refused = r.refused.clone().unwrap_or_default();
    assert!(
        refused.contains("ring in the current is too weak")
            && refused.contains("before any voltage"),
        "{refused}"
    );
    assert_eq!(r.max_command_volts, 0.0);
    let understated = noisy.replace(
        "per_count = 4.8828125e-7",
        "per_count = 4.8828125e-7\nnoise_codes = 2.0",
    );
    let r = run(&understated);
    assert!(
        matches!(r.fault, Some(Fault::Trim(TrimError::Unresolvable { .. }))),
        "{:?}",
        r.fault
    );
    let words = r.fault_words.clone().unwrap_or_default();
    assert!(words.contains("heard in the"), "{words}");
    let trims = |r: &Run| -> Vec<(f64, f64)> {
        (r.events.iter())
            .filter(|e| e.kind == EventKind::Trimmed)
            .map(|e| (e.values[1].1, e.values[4].1))
            .collect()
    };
    let peer = trims(&run(&text));
    for ((hz, resolution), (peer_hz, _)) in trims(&r).into_iter().zip(peer) {
        let claimed = f64::from(TIMING_ERROR_TIMES_RESOLUTION) / resolution;
        assert!(
            (hz / peer_hz - 1.0).abs() <= 4.0 * claimed,
            "{hz} Hz against {peer_hz} Hz, resolution {resolution}"
        );
    }
}

/// Issue 45's barely tunable device (jlim 100, λ1p 4, λ2p 1: 53.52–54.01 Hz) sensorless on a
/// creeping plant (Q 40, a 500 Pa branch over 6 s), the current monitor 1 µA rms at 10 kHz, a
/// 20 V probe at 250 Hz, target 53.81 Hz. The code before timed its first ring at a resolution
/// of 57 and adopted 53.881 Hz (0.13% off, the bias moved 4,016 → 4,985 V). Read directly, the
/// monitor's noise heard in the hold refuses the ring before the pulse (no reading adopted,
/// 0 V at the end); read through the board's ADC (2 codes, which the image declares), the boot
/// refuses it before any voltage.
#[test]
fn the_barely_tunable_device_never_adopts_a_reading_it_cannot_resolve() {
    use de_resonator::{EventKind, TrimError};
    let scene_text = |seed: u32, monitor: &str| {
        format!(
            "name = \"gent\"\nduration_seconds = 2.0\nseed = {seed}\n[device]\njlim = 100.0\n\
             prestretch_1 = 4.0\nprestretch_2 = 1.0\ndamping = 2.8e-4\n[plant]\n\
             quality_factor = 40.0\nbranches = [{{ modulus = 500.0, relaxation_seconds = 6.0 }}]\n\
             leakage_ohms = 1e12\n[amplifier]\nbandwidth_hz = 2000.0\n\
             slew_volts_per_second = 200000.0\n{monitor}[controller]\ntarget_hz = 53.81\n\
             ac_volts = 60.0\nac_hz = 50.0\ntrim_tolerance = 1e-3\nprobe_volts = 20.0\n\
             probe_hz = 250.0\n"
        )
    };
    let run = |text: String| {
        let mut s = scene::parse(&text).unwrap();
        s.run.history = false;
        s.run.run().unwrap()
    };
    for seed in 1..=4 {
        let direct = "[current_monitor]\nnoise_amps = 1e-6\nsample_hz = 10000.0\n\
                      resolution_amps = 1e-7\n";
        let r = run(scene_text(seed, direct));
        assert!(
            matches!(r.fault, Some(Fault::Trim(TrimError::Unresolvable { .. }))),
            "seed {seed}: {:?}",
            r.fault
        );
        assert!(r.events.iter().all(|e| e.kind != EventKind::Trimmed));
        assert!(r.final_membrane_volts.abs() < 1.0, "seed {seed}");
        let adc = "[front_end]\nscan_hz = 10000.0\nnoise_codes = 2.0\n[front_end.current]\n\
                   input = 10\nzero_code = 2048.0\nper_count = 4.8828125e-7\nlow = -9e-4\n\
                   high = 9e-4\n";
        let r = run(scene_text(seed, adc));
        let refused = r.refused.clone().unwrap_or_default();
        assert!(
            refused.contains("before any voltage"),
            "seed {seed}: {refused}"
        );
        assert_eq!(r.max_command_volts, 0.0, "seed {seed}");
    }
}

/// A batch's scene (model.md §10): the image keeps the batch, the boot's cap is (1 − margin)
/// times its guaranteed limit — which no corner of the batch's own limit (each found by the
/// core on its own) lies below — the run never commands above it, and the plant (the soft
/// corner) crosses nothing.
#[test]
fn a_batch_scene_is_capped_by_its_guaranteed_limit() {
    use de_resonator::image::PowerUp;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/batch-vhb.toml");
    let mut s = scene::load(&path).unwrap();
    s.run.history = false;
    let bytes = s.run.image(PowerUp::Drive).unwrap();
    let report = host_sim::cmd::image::describe(&bytes, "batch".into()).unwrap();
    let verdict = serde_json::to_value(&report.verdict).unwrap();
    assert_eq!(verdict["cap_by"], "batch");
    let g = verdict["batch_limit_volts"].as_f64().unwrap();
    let cap = verdict["max_volts"].as_f64().unwrap();
    assert!(
        cap <= 0.95 * g && cap > 0.95 * g * (1.0 - 1e-4),
        "{cap} {g}"
    );
    let b = s.run.batch;
    let mut lowest = f64::INFINITY;
    for corner in 0..8u32 {
        let mut p = b.nominal;
        let pick = |bit: u32, f: de_resonator::Field| {
            if corner & (1 << bit) == 0 {
                b.low.get(f)
            } else {
                b.high.get(f)
            }
        };
        p.shear_modulus = pick(0, de_resonator::Field::ShearModulus);
        p.thickness = pick(1, de_resonator::Field::Thickness);
        p.breakdown_field = pick(2, de_resonator::Field::BreakdownField);
        let limit = Tuner::new(Device::new(p).unwrap()).limit().at.volts;
        assert!(limit >= g, "corner {corner}: {limit} V below {g} V");
        lowest = lowest.min(limit);
    }
    assert!(g >= 0.99 * lowest, "{g} vs {lowest}");
    let nominal = Tuner::new(Device::new(b.nominal).unwrap()).limit().at.volts;
    assert!(cap < 0.85 * nominal);
    let volts = |v: f64| {
        let v = v.round() as u64;
        format!("{},{:03} V", v / 1000, v % 1000)
    };
    documents("batch-vhb.toml", &[volts(cap), volts(g)]);
    let r = s.run.run().unwrap();
    assert!(r.boot.is_some() && r.fault.is_none() && r.plant_crossing.is_none());
    assert!(
        r.max_command_volts <= cap,
        "{} above {cap}",
        r.max_command_volts
    );
}

/// The scene's amplifier is the one its image declares (issue 60): slewing at 20 kV/s, the
/// reference scene's 100 V AC at 40 Hz (2π·40·100 = 25,133 V/s at its zero crossings) is
/// refused at boot with both figures, 0 V throughout; at its 200 kV/s it drives; a
/// `[controller]` that declares another slew rate has the last word.
#[test]
fn a_drive_steeper_than_the_scene_s_amplifier_is_refused_up_front() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/reference.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let run_text = |text: &str| {
        let mut s = scene::parse(text).unwrap();
        s.run.history = false;
        s.run.duration_seconds = 1.0;
        s.run.run().unwrap()
    };
    let slow = text.replace(
        "slew_volts_per_second = 200000.0",
        "slew_volts_per_second = 20000.0",
    );
    let r = run_text(&slow);
    let words = r.refused.clone().unwrap_or_default();
    let slope = std::f64::consts::TAU * 40.0 * 100.0;
    assert!(words.contains("20000 V/s"), "{words}");
    assert!(
        words.contains(&format!("{}", slope as u32)),
        "{slope}: {words}"
    );
    assert_eq!(r.max_command_volts, 0.0);
    assert!(r.plant_crossing.is_none());
    let r = run_text(&text);
    assert!(r.refused.is_none() && r.fault.is_none(), "{:?}", r.refused);
    let told = slow.replace(
        "[controller]",
        "[controller]\namplifier_slew_volts_per_second = 30000.0",
    );
    let r = run_text(&told);
    assert!(r.refused.is_none(), "{:?}", r.refused);
}

/// The scene's amplifier bandwidth is the one its settings declare (issue 60): behind 40 Hz
/// (45° of lag at the drive's 40 Hz), the reference scene's 100 V AC is followed about
/// 71 V off its command (100·sin 45°, more on the switch-on), beyond a watch of 50 V: refused
/// at boot with both figures, 0 V throughout. The same amplifier not declared (a
/// `[controller]` that turns it off) drives, and the watch takes it off running, the
/// amplifier "disagreeing" with its command; at the scene's 2 kHz it drives.
#[test]
fn a_drive_the_scene_s_amplifier_cannot_follow_is_refused_up_front() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/reference.toml");
    let text = std::fs::read_to_string(path).unwrap().replace(
        "[controller]",
        "[controller]\namplifier_tolerance_volts = 50.0",
    );
    let run_text = |text: &str| {
        let mut s = scene::parse(text).unwrap();
        s.run.history = false;
        s.run.duration_seconds = 2.0;
        s.run.run().unwrap()
    };
    let slow = text.replace("bandwidth_hz = 2000.0", "bandwidth_hz = 40.0");
    let r = run_text(&slow);
    let words = r.refused.clone().unwrap_or_default();
    assert!(
        words.contains("amplifier_bandwidth_hz") && words.contains(" 50 V"),
        "{words}"
    );
    let following: f64 = words
        .split(" V off its command")
        .next()
        .and_then(|w| w.rsplit(' ').next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{words}"));
    let settled = 100.0 * std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        following >= settled && following <= 1.1 * settled,
        "{following}: {words}"
    );
    assert_eq!(r.max_command_volts, 0.0);
    assert!(r.plant_crossing.is_none());
    let untold = slow.replace("[controller]", "[controller]\namplifier_bandwidth_hz = 0.0");
    let r = run_text(&untold);
    assert!(r.refused.is_none(), "{:?}", r.refused);
    let fault = r.fault_words.clone().unwrap_or_default();
    assert!(fault.contains("amplifier gives"), "{fault}");
    let r = run_text(&text);
    assert!(
        r.refused.is_none() && r.fault.is_none(),
        "{:?} {:?}",
        r.refused,
        r.fault
    );
}

/// On the board the batch holds (model.md §10), by the self-sensed stretch at the held bias:
/// the membrane 6% further pre-stretched than the batch's (exact) pre-stretch faults, saying
/// the stretch from C against the batch's band there, each figure the scene's own (the
/// plant's stretch at its end and the band from the image's table, both recomputed here);
/// membranes at the batch's corners and centre drive on.
#[test]
fn the_self_sensed_stretch_outside_the_batch_faults_and_inside_it_drives() {
    use de_resonator::model::guaranteed::Leaf;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fault-outside-batch.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let run_with = |plant: &str| {
        let text = text.replace("prestretch_scale = 1.06", plant);
        let mut s = scene::parse(&text).unwrap();
        s.run.history = false;
        (s.run.run().unwrap(), s.run.batch)
    };
    let (outside, b) = run_with("prestretch_scale = 1.06");
    assert!(!b.is_exact());
    let Some(Fault::OutsideBatch {
        stretch,
        sigma,
        low,
        high,
        volts,
    }) = outside.fault
    else {
        panic!("{:?}", outside.fault_words);
    };
    assert!(outside
        .fault_words
        .unwrap()
        .contains("not what the image declares"));
    assert_eq!(outside.final_command_volts, 0.0);
    assert!(outside.plant_crossing.is_none());
    // The band at the held bias holds the band every device of the batch has there, through
    // the file's C1 (the probe's), and the plant's C there lies above it.
    let (c_low, c_high) = b
        .capacitance_farads(f64::from(volts), &mut vec![Leaf::default(); 4096])
        .unwrap();
    let c1 = b.nominal.farads_per_stretch_squared();
    assert!(
        f64::from(low) <= (c_low / c1).sqrt() * (1.0 + 1e-6),
        "{low}"
    );
    assert!(
        f64::from(high) >= (c_high / c1).sqrt() * (1.0 - 1e-6),
        "{high}"
    );
    // The membrane's: λ2p 6% up makes its C1 1.06² the file's; λ itself rises too.
    assert!(
        f64::from(stretch) > 1.06 * f64::from(low),
        "{stretch} {low}"
    );
    assert!(
        stretch - 4.0 * sigma > high,
        "{stretch} ± {sigma} against {high}"
    );
    for plant in [
        "shear_modulus_scale = 0.9",
        "shear_modulus_scale = 1.1",
        "prestretch_scale = 1.0",
    ] {
        let (inside, _) = run_with(plant);
        assert!(inside.fault.is_none(), "{plant}: {:?}", inside.fault_words);
    }
}

/// On the board the batch holds (model.md §10): a trim on a plant whose μ lies outside the
/// batch's faults, naming μ and both figures, down at the slew rate; one inside it tunes.
#[test]
fn a_trim_outside_the_batch_faults_and_inside_it_tunes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/batch-vhb.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let with = |scale: f64| {
        let text = text
            .replace(
                "shear_modulus_scale = 0.9",
                &format!("shear_modulus_scale = {scale}"),
            )
            .replace(
                "target_hz = 45.5\nac_volts = 100.0",
                // 100 V at 40 Hz swings a corner of the batch (f 41 Hz at the bias, no
                // damping told) across breakdown: 91 V fits.
                "target_hz = 44.5\ntrim_tolerance = 1e-3\nac_volts = 80.0",
            );
        let mut s = scene::parse(&text).unwrap();
        s.run.history = false;
        s.run.run().unwrap()
    };
    let inside = with(0.95);
    assert!(inside.boot.is_some(), "{:?}", inside.refused);
    assert!(inside.fault.is_none(), "{:?}", inside.fault_words);
    let error = inside.natural_frequency_hz / 44.5 - 1.0;
    assert!(error.abs() < 1e-3, "{error}");
    let outside = with(0.8);
    let words = outside.fault_words.clone().unwrap_or_default();
    assert!(
        words.contains("not what the image declares") && words.contains("shear_modulus"),
        "{words}"
    );
    assert!(outside.plant_crossing.is_none());
    assert!(
        outside.final_command_volts == 0.0,
        "{}",
        outside.final_command_volts
    );
    // Said with both figures: the μ measured (36 kPa) and the batch's 40.5–49.5 kPa.
    assert!(
        words.contains("40500") && words.contains("49500"),
        "{words}"
    );
}

/// Issue 60's scene (`q-measured.toml`): the reference file, no damping told, its plant of
/// Q 200 at 44 Hz, and an AC at 44 Hz of 0.5% of the bias. Before, the boot refused it (no
/// bound without a Q); now the AC waits for the trims, whose rings give Q: each within 10%
/// of the plant's at the frequency measured (a fixed damping: Q = 200·f/44), the highest its
/// window allows at or above it. The drive starts after the last trim and runs to the end,
/// nothing faults, and the plant crosses nothing.
#[test]
fn the_board_measures_q_and_drives_at_the_resonance() {
    let r = run("q-measured.toml");
    assert!(r.refused.is_none() && r.fault.is_none(), "{r:?}");
    assert_eq!(r.plant_crossing, None);
    let value = |said: &Said, name: &str| {
        said.values
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(f64::NAN, |&(_, v)| v)
    };
    let trims: Vec<&Said> = r
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Trimmed)
        .collect();
    assert!(trims.len() >= 2, "{:?}", r.events);
    for said in &trims {
        let plant_q = 200.0 * value(said, "measured_hz") / 44.0;
        let (q, high) = (value(said, "quality_factor"), value(said, "quality_high"));
        assert!((q / plant_q - 1.0).abs() < 0.1, "{plant_q}: {said:?}");
        assert!(high >= plant_q, "{plant_q}: {said:?}");
    }
    let on = r.events.iter().position(|e| e.kind == EventKind::DriveOn);
    let on = on.unwrap_or_else(|| panic!("{:?}", r.events));
    assert_eq!(r.events[on - 1].kind, EventKind::Trimmed);
    assert!(r.events[on].seconds < 3.0, "{:?}", r.events);
    let last = trims.last().unwrap();
    documents(
        "q-measured.toml",
        &[
            format!("{} trims", trims.len()),
            format!(
                "Q {:.0} (at most {:.0})",
                value(last, "quality_factor"),
                value(last, "quality_high")
            ),
            format!("{:.3} s", r.events[on].seconds),
        ],
    );
}
