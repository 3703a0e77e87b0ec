//! Fuzz test of the f32 controller (issue 12): random valid and invalid devices, settings,
//! amplifiers and tables (made by the project's writer, then corrupted: bits flipped, or
//! values changed and resealed with a fresh CRC), and sensor and amplifier-monitor samples
//! (a simulated plant, mismatched or not, noisy, NaN, stuck, wild). Every tick's command is
//! checked against (1 − margin)·Φlimit of the device flashed, computed in f64; after a fault
//! the output goes down at the slew rate, no faster, to 0 V and stays; the final gate never fires (the boot checks catch everything first).
//!
//! `FUZZ_TICKS` (default 10⁶) sets how many ticks to check, `FUZZ_SEED` the seed. A longer
//! run: `FUZZ_TICKS=100000000 cargo test --release --test fuzz -- --nocapture`.

mod common;

use common::reseal;

use std::collections::BTreeMap;

use common::{made_table, random_device, Rng};
use de_resonator::table::{self, HEADER_BYTES, POINT_BYTES};
use de_resonator::{
    Amplifier, Controller, DacCode, Device, DeviceParams, Drive, Event, Fault, FaultStage, Inputs,
    Integrator, Method, Settings, State, Tuner,
};

/// A value that breaks something: NaN, infinities, zero, negatives, huge and tiny.
fn wild(rng: &mut Rng) -> f64 {
    let picks = [
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        0.0,
        -1.0,
        1e30,
        1e-30,
        -1e-3,
    ];
    match rng.below(3) {
        0 => picks[rng.below(picks.len())],
        1 => rng.range(-1e6, 1e6),
        _ => rng.log_range(1e-12, 1e12) * if rng.unit() < 0.5 { -1.0 } else { 1.0 },
    }
}

/// Sometimes a wild value in one parameter.
fn maybe_broken(rng: &mut Rng, mut p: DeviceParams<f64>) -> DeviceParams<f64> {
    if rng.unit() < 0.1 {
        let v = wild(rng);
        match rng.below(6) {
            0 => p.shear_modulus = v,
            1 => p.prestretch_1 = v,
            2 => p.prestretch_2 = v,
            3 => p.thickness = v,
            4 => p.jlim = Some(v),
            _ => p.breakdown_field = v,
        }
    }
    p
}

/// The little-endian f32 at `at`.
fn f32_at(bytes: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

/// The f32 at `at` scaled by 0.5 to `most`, or wild (half the time each), then resealed.
fn change_value(rng: &mut Rng, bytes: &mut [u8], at: usize, most: f64) {
    let v = f64::from(f32_at(bytes, at));
    let new = if rng.unit() < 0.5 {
        v * rng.range(0.5, most)
    } else {
        wild(rng)
    };
    bytes[at..at + 4].copy_from_slice(&(new as f32).to_le_bytes());
    reseal(bytes);
}

/// The table as made, or corrupted one way or another; and the kind, for the summary.
fn corrupt(rng: &mut Rng, mut bytes: Vec<u8>) -> (Vec<u8>, &'static str) {
    let n = bytes.len();
    let points = (n - HEADER_BYTES - 4) / POINT_BYTES;
    let kind = match rng.below(8) {
        0..=2 => "clean",
        3 => {
            let at = rng.below(n);
            bytes[at] ^= 1 << rng.below(8);
            "bit flipped"
        }
        4 => {
            // A value in the points, changed and resealed.
            let at = HEADER_BYTES + 4 * rng.below(2 * points);
            change_value(rng, &mut bytes, at, 1.5);
            "point resealed"
        }
        5 => {
            // The whole bias column scaled, resealed: a consistent but wrong table.
            let scale = rng.range(0.9, 1.2) as f32;
            for k in 0..points {
                let at = HEADER_BYTES + POINT_BYTES * k + 4;
                let v = f32_at(&bytes, at) * scale;
                bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            reseal(&mut bytes);
            "biases scaled, resealed"
        }
        6 => {
            // A header value (parameter, margin, error), changed and resealed.
            let at = 8 + 4 * rng.below(15);
            change_value(rng, &mut bytes, at, 2.0);
            "header resealed"
        }
        _ => {
            bytes.truncate(rng.below(n));
            "truncated"
        }
    };
    (bytes, kind)
}

/// Settings around the defaults for a margin and a target whose bias is `bias_volts`,
/// sometimes wild.
fn settings(
    rng: &mut Rng,
    margin: f64,
    target_hz: f64,
    bias_volts: f64,
    limit_volts: f64,
    f0: f64,
) -> Settings {
    let mut s = Settings::for_target(target_hz as f32);
    s.margin = margin as f32;
    s.slew_volts_per_second = (limit_volts * rng.range(0.5, 20.0)) as f32;
    s.tick_hz = [500.0, 1000.0, 2000.0][rng.below(3)];
    s.settle_seconds = rng.range(0.0, 0.3) as f32;
    s.check_seconds = rng.range(0.05, 0.3) as f32;
    if rng.unit() < 0.6 {
        // Mostly an AC the plan holds (below the bias, a few % of the limit); sometimes not.
        let most = if rng.unit() < 0.8 {
            (0.5 * bias_volts).min(0.05 * limit_volts)
        } else {
            0.3 * limit_volts
        };
        s.ac_volts = (most * rng.log_range(1e-3, 1.0)) as f32;
        s.ac_hz = (f0 * rng.range(0.1, 2.5)).min(0.45 * f64::from(s.tick_hz)) as f32;
    }
    if cfg!(feature = "trim") && rng.unit() < 0.25 {
        s.trim_tolerance = Some(1e-3);
        s.trim_window_seconds = 0.25;
        s.trim_every_seconds = [None, Some(0.5)][rng.below(2)];
    }
    if rng.unit() < 0.15 {
        let v = wild(rng) as f32;
        match rng.below(8) {
            0 => s.target_hz = v,
            1 => s.margin = v,
            2 => s.slew_volts_per_second = v,
            3 => s.tick_hz = v,
            4 => s.ac_volts = v,
            5 => s.ac_hz = v,
            6 => s.trim_pulse_volts = v,
            _ => s.agreement = v,
        }
    }
    s
}

/// How the sensors behave in one case.
#[derive(Clone, Copy)]
enum Sensor {
    None,
    Plant { noise: f64 },
    NanAt(u32),
    StuckAt(u32),
    Wild,
}

#[derive(Default)]
struct Tally {
    cases: u64,
    started: u64,
    ticks: u64,
    refused: BTreeMap<String, u64>,
    faults: BTreeMap<String, u64>,
    tables: BTreeMap<&'static str, u64>,
    held: u64,
}

fn kind<T: std::fmt::Debug>(x: &T) -> String {
    let text = format!("{x:?}");
    text.split(['(', ' ', '{'])
        .next()
        .unwrap_or_default()
        .to_string()
}

#[test]
fn fuzz_the_controller() {
    let ticks_wanted: u64 = std::env::var("FUZZ_TICKS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x00f0_0d5e_ed12);
    let mut rng = Rng(seed | 1);
    let mut tally = Tally::default();
    while tally.ticks < ticks_wanted {
        tally.cases += 1;
        let nominal = random_device(&mut rng);
        let (Ok(d64), Ok(_)) = (Device::new(nominal), Device::new(nominal.cast::<f32>())) else {
            continue;
        };
        let tuner = Tuner::new(d64);
        let limit = tuner.limit().at.volts;
        let f0 = tuner.zero_bias().natural_frequency_hz;
        // The table's margin, and the settings' (mostly the same or larger).
        let table_margin = [0.0, 0.05, 0.1][rng.below(3)];
        let margin = if rng.unit() < 0.8 {
            table_margin + rng.range(0.0, 0.2)
        } else {
            rng.range(0.0, 0.3)
        };
        let range = tuner
            .tunable_range(table::table_margin(margin.max(table_margin)))
            .unwrap();
        let u = if rng.unit() < 0.9 {
            rng.range(0.01, 0.99)
        } else {
            rng.range(-0.05, 1.05)
        };
        let target = range.low_hz + (range.high_hz - range.low_hz) * u;
        let bias = tuner.tune(target, margin).map_or(0.0, |e| e.volts);
        let (bytes, table_kind) = corrupt(&mut rng, made_table(nominal, table_margin, 64));
        *tally.tables.entry(table_kind).or_default() += 1;
        // The device flashed: as made, sometimes another (the table is not for it).
        let flashed = if rng.unit() < 0.05 {
            random_device(&mut rng)
        } else {
            maybe_broken(&mut rng, nominal)
        };
        let s = settings(&mut rng, margin, target, bias, limit, f0);
        let full_scale = limit
            * if rng.unit() < 0.9 {
                rng.range(1.0, 2.0)
            } else {
                rng.range(0.3, 1.0)
            };
        let Ok(amplifier) = Amplifier::new(2.5, (full_scale / 2.5) as f32) else {
            continue;
        };
        let started = Controller::start(flashed.cast(), &bytes, amplifier, s);
        let mut c = match started {
            Ok((c, _)) => c,
            Err(fault) => {
                assert_eq!(fault.stage(), FaultStage::Boot, "{fault}");
                *tally.refused.entry(kind(&fault)).or_default() += 1;
                continue;
            }
        };
        tally.started += 1;
        // The yardstick: the f64 limit of the device flashed, as the controller holds it.
        let flashed64: DeviceParams<f64> = flashed.cast::<f32>().cast();
        let cap = (1.0 - f64::from(s.margin))
            * Tuner::new(Device::new(flashed64).unwrap()).limit().at.volts;

        // The plant: the device flashed, its μ off by up to ±25% in one case of three, Q 100.
        let mut plant = flashed64;
        if rng.unit() < 0.33 {
            plant.shear_modulus *= rng.range(0.75, 1.25);
        }
        let ticks = 200 + rng.below(3000) as u32;
        let sensor = match rng.below(6) {
            0 => Sensor::None,
            1 => Sensor::NanAt(rng.below(ticks as usize) as u32),
            2 => Sensor::StuckAt(rng.below(ticks as usize) as u32),
            3 => Sensor::Wild,
            _ => Sensor::Plant {
                noise: rng.log_range(1e-7, 1e-3),
            },
        };
        let monitor_amplifier = rng.below(3);
        let bus_fails = (rng.unit() < 0.1).then(|| rng.below(ticks as usize) as u32);
        plant.damping = plant.effective_mass() * std::f64::consts::TAU * f0 / 100.0;
        let mut model = Device::new(plant).ok().and_then(|d| {
            let rest = State {
                stretch: d.prestretch_1(),
                velocity: 0.0,
            };
            let step = 1.0 / f64::from(s.tick_hz);
            let drive = Drive::constant(&d, 0.0);
            Integrator::new(d, drive, Method::Rk4, step, d.model_range(), rest, true).ok()
        });
        let (mut faulted, mut last_volts, mut stuck) = (None, 0.0f32, f32::NAN);
        let slew_step = s.slew_volts_per_second / s.tick_hz;
        let lsb_volts = amplifier.volts(DacCode(1));
        for k in 0..ticks {
            let truth = model.as_ref().map(|m| m.state().stretch as f32);
            let stretch = match sensor {
                Sensor::None => None,
                Sensor::Plant { noise } => truth.map(|l| l + (noise * rng.range(-1.0, 1.0)) as f32),
                Sensor::NanAt(at) => truth.map(|l| if k == at { f32::NAN } else { l }),
                Sensor::StuckAt(at) => {
                    if k == at {
                        stuck = truth.unwrap_or(2.0);
                    }
                    if k >= at {
                        Some(stuck)
                    } else {
                        truth
                    }
                }
                Sensor::Wild => Some(wild(&mut rng) as f32),
            };
            let amplifier_volts = match monitor_amplifier {
                0 => None,
                1 => Some(last_volts + rng.range(-5.0, 5.0) as f32),
                _ => Some(if rng.unit() < 0.01 {
                    wild(&mut rng) as f32
                } else {
                    last_volts
                }),
            };
            // The current monitor: absent, the plant's speed as a current (what self-sensing
            // trims on when there is no stretch), or wild (NaN, infinite, huge) at times.
            let current_amps = match monitor_amplifier {
                0 => None,
                1 => model.as_ref().map(|m| (m.state().velocity * 1e-6) as f32),
                _ => Some(if rng.unit() < 0.01 {
                    wild(&mut rng) as f32
                } else {
                    rng.range(-1e-5, 1e-5) as f32
                }),
            };
            let mut out = c.tick(Inputs {
                stretch,
                amplifier_volts,
                current_amps,
            });
            if bus_fails == Some(k) {
                out = c.fault(Fault::Bus);
            }
            tally.ticks += 1;
            assert!(
                out.volts >= 0.0 && f64::from(out.volts) <= cap,
                "tick {k}: {} V above {cap} V: {flashed:?} {s:?}",
                out.volts
            );
            assert_eq!(out.volts, amplifier.volts(out.code));
            if let Some(Event::Fault(fault)) = out.event {
                assert!(
                    !matches!(fault, Fault::Gate { .. }),
                    "the final gate fired: {fault} {flashed:?} {s:?}"
                );
                *tally.faults.entry(kind(&fault)).or_default() += 1;
                faulted = Some((k, last_volts));
            }
            if let Some((at, from_volts)) = faulted {
                // After a fault: down at the slew rate, never faster (at once where the bus
                // died), to 0 V within the ticks the slew needs, and 0 V from then on.
                let dead_bus = bus_fails.is_some_and(|b| b <= k);
                let drop = last_volts - out.volts;
                assert!(drop >= 0.0, "tick {k}: up {} V after a fault", -drop);
                assert!(
                    dead_bus || drop <= slew_step + lsb_volts,
                    "tick {k}: down {drop} V in a tick after a fault, slew {slew_step} V"
                );
                let needed = (from_volts / slew_step).ceil() as u32 + 1;
                assert!(
                    k - at < needed || out.code.0 == 0,
                    "tick {k}: {} V, {} ticks after the fault from {from_volts} V",
                    out.volts,
                    k - at
                );
            }
            if let Some(Event::AboveCeiling { .. }) = out.event {
                tally.held += 1;
            }
            // The trim's solve, outside the tick (now and then late, as a busy task is).
            #[cfg(feature = "trim")]
            if rng.unit() < 0.5 {
                if let Some(job) = c.trim_job() {
                    c.trim_done(job.solve());
                }
            }
            last_volts = out.volts;
            if let Some(m) = model.as_mut() {
                let d = *m.device();
                let moved = m
                    .set_drive(Drive::constant(&d, f64::from(out.volts)))
                    .and_then(|_| m.step());
                if moved.is_err() {
                    model = None;
                }
            }
        }
    }
    println!(
        "fuzz: {} cases ({} started), {} checked ticks, 0 above (1 - margin)·limit, every fault \
         down at the slew rate to 0 V, {} trims held at the ceiling",
        tally.cases, tally.started, tally.ticks, tally.held
    );
    println!("fuzz: tables {:?}", tally.tables);
    println!("fuzz: refused at boot {:?}", tally.refused);
    println!("fuzz: faults while running {:?}", tally.faults);
    // Most cases with a clean table must start, or the ticks check little.
    let clean = tally.tables.get("clean").copied().unwrap_or_default();
    assert!(
        2 * tally.started > clean,
        "too few started: {} of {clean}",
        tally.started
    );
}
