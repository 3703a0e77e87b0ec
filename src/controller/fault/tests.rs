//! One fault of every kind: each comes back from its figures whole, the layout's positions
//! keep their order, entries logged by earlier firmware read as they did.

extern crate std;
use std::format;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

use super::figures::{DETAILS, VALUES};
use super::*;
use crate::acquire::{Channel, Stall};
use crate::estimate::ring::{NoiseFrom, RingInput};
use crate::model::device::{Field, Problem, SCALES};
use crate::model::motion::{Drive, Method};
use crate::model::swing::Resonance;

/// A field's value for `Fault::samples`: the `k`-th of a fault's fields (from 1), each different.
pub(super) trait Sample {
    fn sample(k: u32) -> Self;
}

impl Sample for f32 {
    fn sample(k: u32) -> f32 {
        k as f32 * 1.375 - 2.0
    }
}

impl Sample for u32 {
    fn sample(k: u32) -> u32 {
        k * 1009
    }
}

/// Choices by position, each a different one as far as the list goes.
macro_rules! sample_by_position {
    ($($ty:ty => $all:expr,)*) => {$(
        impl Sample for $ty {
            fn sample(k: u32) -> $ty {
                $all[k as usize % $all.len()]
            }
        }
    )*};
}

sample_by_position! {
    Setting => Setting::ALL,
    FailureMode => FailureMode::ALL,
}

// Nested errors: one variant each (every variant of each is in `logged_in_dg`).
impl Sample for ParamError {
    fn sample(k: u32) -> ParamError {
        ParamError {
            field: Field::ALL[k as usize % Field::ALL.len()],
            problem: Problem::UnsafeAtZeroBias {
                mode: Sample::sample(k + 1),
            },
        }
    }
}

impl Sample for TableError {
    fn sample(k: u32) -> TableError {
        TableError::BadCrc {
            stored: k,
            computed: k + 1,
        }
    }
}

impl Sample for TuneError<f32> {
    fn sample(k: u32) -> TuneError<f32> {
        TuneError::OutOfRange {
            target_hz: Sample::sample(k),
            low_hz: Sample::sample(k + 1),
            high_hz: Sample::sample(k + 2),
        }
    }
}

impl Sample for StepError<f32> {
    fn sample(k: u32) -> StepError<f32> {
        StepError::LeftGuardedRange {
            tick: k.into(),
            stretch: Sample::sample(k),
        }
    }
}

impl Sample for CodeError {
    fn sample(k: u32) -> CodeError {
        CodeError::OutOfRange {
            volts: Sample::sample(k),
            max_volts: Sample::sample(k + 1),
        }
    }
}

impl Sample for InputError {
    fn sample(k: u32) -> InputError {
        InputError::Stalled {
            stall: Stall::ALL[k as usize % Stall::ALL.len()],
            recovered: k,
        }
    }
}

impl Sample for TrimError {
    fn sample(k: u32) -> TrimError {
        TrimError::NoEstimate {
            measured_hz: Sample::sample(k),
            volts: Sample::sample(k + 1),
        }
    }
}

impl Sample for SwingError<f32> {
    fn sample(k: u32) -> SwingError<f32> {
        SwingError::Unbounded {
            resonance: Resonance::ALL[k as usize % Resonance::ALL.len()],
            natural_hz: Sample::sample(k),
            quality_factor: Sample::sample(k + 1),
            largest_ac_volts: Sample::sample(k + 2),
        }
    }
}

/// One fault of each kind (`Fault::samples`, made from the declaration) and every fault of
/// `logged_in_dg`.
fn every_fault() -> Vec<Fault> {
    let mut all = logged_in_dg();
    all.extend(Fault::samples());
    all
}

/// One fault of every kind and sub-kind there was in the log's layout `DG`, its figures'
/// numbers all different (tests/golden/fault-figures-dg.txt holds their figures and words as
/// that firmware wrote them: kept as it is, a new fault is covered by `Fault::samples`).
fn logged_in_dg() -> Vec<Fault> {
    let (a, b, c, d, e) = (1.25f32, -2.5e-3, 7449.878, 9361.898, 44.0);
    let mode = FailureMode::LossOfTension2b;
    let mut all = vec![
        Fault::Setting {
            setting: Setting::ALL[7],
            value: a,
        },
        Fault::Swing {
            setting: Setting::ALL[6],
            value: a,
            low_volts: b,
            high_volts: c,
            max_volts: d,
        },
        Fault::Disagree {
            table_volts: a,
            table_hz: b,
            solved_volts: c,
            solved_hz: d,
        },
        Fault::AboveSafe {
            volts: c,
            max_volts: d,
        },
        Fault::PlanCrosses { mode, seconds: a },
        Fault::Gate {
            volts: c,
            max_volts: d,
        },
        Fault::Sensor { value: f32::NAN },
        Fault::SensorImplausible {
            value: a,
            low: b,
            high: c,
        },
        Fault::SensorStuck {
            samples: 100,
            value: 2.211351,
        },
        Fault::Leakage {
            ohms: 7.8e9,
            floor_ohms: 1e10,
        },
        Fault::LeakageFalling {
            ohms: 7.8e9,
            previous_ohms: 1e11,
        },
        Fault::TrackLost {
            drive_hz: a,
            target_hz: e,
        },
        Fault::AmplifierDisagrees {
            commanded_volts: c,
            measured_volts: d,
        },
        Fault::Limit {
            mode,
            tick: 123_456,
        },
        Fault::Bus,
        Fault::NearLimit {
            mode,
            tick: 99,
            stretch: a,
            volts: c,
        },
        Fault::OutsideBatch {
            stretch: a,
            sigma: 1.5e-4,
            low: b,
            high: e,
            volts: c,
        },
        Fault::Steeper {
            setting: Setting::AcVolts,
            volts_per_second: 25_132.7,
            amplifier_volts_per_second: 20_000.0,
        },
        Fault::SwingOutgrown {
            tick: 1352,
            half_span: b,
            growth: 3.5e-5,
            allowed: 1.5e-3,
            quality_factor: 201.0,
        },
        Fault::DropRings {
            from_volts: c,
            mode,
        },
        Fault::AmplifierLags {
            setting: Setting::AcVolts,
            following_volts: 214.6,
            tolerance_volts: 200.0,
        },
    ];
    let problems = [
        Problem::NotFinite,
        Problem::NotPositive,
        Problem::Negative,
        Problem::NoTension1AtZeroBias,
        Problem::NoTension2AtZeroBias,
        Problem::StretchLimitAtZeroBias,
        Problem::UnsafeAtZeroBias { mode },
        Problem::DerivedNotFinite { scale: SCALES[4] },
    ];
    all.extend(problems.map(|problem| {
        Fault::Device(ParamError {
            field: Field::ALL[12],
            problem,
        })
    }));
    all.extend(
        [
            TableError::TooShort { bytes: 12 },
            TableError::BadMagic,
            TableError::UnsupportedVersion { version: 9 },
            TableError::BadCount { points: 1 },
            TableError::WrongLength {
                expected: 400,
                bytes: 399,
            },
            TableError::BadCrc {
                stored: 0xDEAD_BEEF,
                computed: 0x0123_4567,
            },
            TableError::NotFinite { index: 3 },
            TableError::NotMonotone { index: 4 },
            TableError::OtherDevice {
                field: Field::ALL[5],
            },
            TableError::OutOfRange {
                target_hz: 55.9,
                low_hz: 42.99,
                high_hz: 45.95,
            },
            TableError::BufferTooSmall { needed: 4096 },
            TableError::BadBatch {
                field: Some(Field::Thickness),
            },
            TableError::BadBatch { field: None },
            TableError::BadCapacitance { index: 15 },
        ]
        .map(Fault::Table),
    );
    all.extend(
        [
            TuneError::InvalidTarget { target_hz: b },
            TuneError::InvalidMargin { margin: 1.5 },
            TuneError::OutOfRange {
                target_hz: 55.9,
                low_hz: 42.99,
                high_hz: 45.95,
            },
        ]
        .map(Fault::Tune),
    );
    all.extend(
        [
            StepError::InvalidStep { step_seconds: b },
            StepError::InvalidDrive {
                drive: Drive {
                    bias: a,
                    ac: b,
                    omega: c,
                },
            },
            StepError::InvalidRange { low: a, high: b },
            StepError::Unstable {
                method: Method::ALL[2],
                step_seconds: a,
                max_step_seconds: b,
            },
            StepError::LeftGuardedRange {
                tick: 77,
                stretch: a,
            },
            StepError::NewtonFailed { tick: 78 },
            StepError::NonFinite { tick: 79 },
            StepError::DriveNotGuarded {
                least_bias_dimless_squared: a,
                guarded_bias_dimless_squared: b,
            },
        ]
        .map(Fault::PlanFailed),
    );
    all.extend(
        [
            CodeError::BadFullScale { volts: b },
            CodeError::OutOfRange {
                volts: c,
                max_volts: d,
            },
            CodeError::BadRail { volts: b },
        ]
        .map(Fault::Amplifier),
    );
    all.extend(
        [
            InputError::NoSamples {
                channel: Channel::ALL[1],
            },
            InputError::Stalled {
                stall: Stall::ALL[1],
                recovered: 2,
            },
            InputError::NotACode {
                channel: Channel::ALL[2],
                code: 4097,
            },
            InputError::AtRail {
                channel: Channel::ALL[0],
                mean_code: 4095.5,
            },
            InputError::Implausible {
                channel: Channel::ALL[2],
                reading: a,
                low: b,
                high: c,
            },
        ]
        .map(Fault::Input),
    );
    all.extend(
        [
            TrimError::NoRing { crossings: 3 },
            TrimError::NoEstimate {
                measured_hz: a,
                volts: c,
            },
            TrimError::NotConverged {
                measured_hz: a,
                target_hz: e,
            },
            TrimError::Unresolvable {
                input: RingInput::ALL[1],
                from: NoiseFrom::ALL[2],
                resolution: a,
                needed: b,
                ring: c,
                noise: d,
            },
            TrimError::OutsideBatch {
                shear_modulus: a,
                low: b,
                high: c,
            },
        ]
        .map(Fault::Trim),
    );
    all.extend(
        [
            SwingError::NoEquilibrium { bias_volts: c },
            SwingError::Unbounded {
                resonance: Resonance::ALL[2],
                natural_hz: e,
                quality_factor: 200.0,
                largest_ac_volts: a,
            },
            SwingError::Crosses {
                mode,
                resonance: Some(Resonance::ALL[3]),
                low_stretch: a,
                high_stretch: b,
                natural_hz: c,
                quality_factor: d,
                largest_ac_volts: e,
            },
            SwingError::Crosses {
                mode,
                resonance: None,
                low_stretch: a,
                high_stretch: b,
                natural_hz: c,
                quality_factor: d,
                largest_ac_volts: e,
            },
        ]
        .map(Fault::DriveSwing),
    );
    all
}

/// Each fault's key is its variant's name in snake case (read from `Debug`): two keys
/// swapped in the declaration fail here (their numbers' order fails at compile time).
#[test]
fn each_faults_key_is_its_variants_name() {
    for fault in every_fault() {
        let debug = format!("{fault:?}");
        let name: String = debug.chars().take_while(|c| c.is_alphanumeric()).collect();
        let mut snake = String::new();
        for (k, c) in name.chars().enumerate() {
            if c.is_uppercase() && k > 0 {
                snake.push('_');
            }
            snake.push(c.to_ascii_lowercase());
        }
        assert_eq!(
            Fault::key_of(fault.number()),
            Some(snake.as_str()),
            "{debug}"
        );
    }
}

#[test]
fn every_fault_comes_back_from_its_figures_with_its_sentence_whole() {
    let all = every_fault();
    // Every kind of fault is among them.
    for number in 1..=FAULT_KEYS.len() as u8 {
        assert!(all.iter().any(|f| f.number() == number), "fault {number}");
    }
    for fault in all {
        let back = Fault::from_figures(&fault.figures());
        // NaN is not equal to itself: compared by its sentence, as the log shows it.
        assert_eq!(
            back.map(|b| b.to_string()),
            Some(fault.to_string()),
            "{fault:?}"
        );
        if let Fault::Sensor { .. } = fault {
            continue;
        }
        assert_eq!(back, Some(fault));
    }
}

/// The lists whose positions flash holds, in their order: a reorder would read an older
/// entry as another fault (the names written out here, not taken from the code).
#[test]
fn the_positions_flash_holds_keep_their_order() {
    // `Setting::ALL`'s order is pinned where the settings are (tests/controller.rs,
    // `every_setting_by_its_key`).
    let fields: Vec<&str> = Field::ALL.iter().map(|f| f.key()).collect();
    assert_eq!(
        fields,
        [
            "shear_modulus",
            "jlim",
            "relative_permittivity",
            "density",
            "breakdown_field",
            "thickness",
            "length_active",
            "length_passive",
            "width",
            "bar_mass",
            "prestretch_1",
            "prestretch_2",
            "damping",
        ]
    );
    assert_eq!(
        FailureMode::ALL,
        [
            FailureMode::DeviceInstability,
            FailureMode::Emi,
            FailureMode::LossOfTension1,
            FailureMode::LossOfTension2a,
            FailureMode::LossOfTension2b,
            FailureMode::Breakdown,
            FailureMode::StretchLimit,
        ]
    );
    assert_eq!(
        Channel::ALL,
        [Channel::Current, Channel::Amplifier, Channel::Stretch]
    );
    assert_eq!(Stall::ALL, [Stall::Overrun, Stall::TransferError]);
    assert_eq!(
        Method::ALL,
        [Method::Rk4, Method::Verlet, Method::ImplicitMidpoint]
    );
    assert_eq!(
        Resonance::ALL,
        [
            Resonance::Harmonic,
            Resonance::SuperHarmonic,
            Resonance::Parametric,
            Resonance::Static
        ]
    );
    assert_eq!(RingInput::ALL, [RingInput::Stretch, RingInput::Charge]);
    assert_eq!(
        NoiseFrom::ALL,
        [NoiseFrom::Image, NoiseFrom::Hold, NoiseFrom::Window]
    );
    assert_eq!(
        SCALES,
        ["H·√(μ/ε)", "μ·L2·H/M", "E_B·√(ε/μ)", "L1A/L1B", "c·T0/M"]
    );
    // A fault's figures as the layout has them: number 14, no index, the count and the
    // sample's bits.
    let stuck = Fault::SensorStuck {
        samples: 100,
        value: 2.5,
    }
    .figures();
    assert_eq!(
        stuck,
        Figures {
            number: 14,
            details: [0; DETAILS],
            values: [100, 0x4020_0000, 0, 0, 0, 0, 0],
        }
    );
    // An outgrown swing logged before its Q was kept (four numbers): Q 0, the sentence
    // as it was then, without a Q.
    let before = Figures {
        number: 27,
        details: [0; DETAILS],
        values: [1352, 0x3a80_0000, 0, 0x3a80_0000, 0, 0, 0],
    };
    let read = Fault::from_figures(&before);
    assert!(
        matches!(read, Some(Fault::SwingOutgrown { tick: 1352, quality_factor, .. })
            if quality_factor == 0.0),
        "{read:?}"
    );
    let said = read.map(|f| f.to_string()).unwrap_or_default();
    assert!(!said.contains(" Q "), "{said}");
    let now = Fault::SwingOutgrown {
        tick: 1352,
        half_span: 1e-3,
        growth: 0.0,
        allowed: 1e-3,
        quality_factor: 201.0,
    };
    assert!(format!("{now}").contains("at Q 201 widened"), "{now}");
}

#[test]
fn any_bytes_give_a_fault_or_none_never_a_panic() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut read = 0;
    for _ in 0..200_000 {
        let r = next();
        let fig = Figures {
            number: (r % (FAULT_KEYS.len() as u64 + 2)) as u8,
            details: [
                (r >> 8) as u8 % 14,
                (r >> 16) as u8 % 14,
                (r >> 24) as u8,
                0,
            ],
            values: [next() as u32; VALUES].map(|v| v ^ next() as u32),
        };
        if let Some(fault) = Fault::from_figures(&fig) {
            read += 1;
            let _ = fault.to_string();
        }
    }
    assert!(read > 10_000, "{read}");
}

/// Entries the firmware wrote in the log's layout `DG` before the faults were declared in one
/// list (tests/golden/fault-figures-dg.txt: one fault of every kind and sub-kind, as that
/// firmware wrote its figures, and its sentence then) read as they did, and the same faults
/// write the same figures now.
#[test]
fn entries_logged_before_read_as_they_did() {
    let golden = include_str!("../../../tests/golden/fault-figures-dg.txt");
    let all = logged_in_dg();
    assert_eq!(golden.lines().count(), all.len());
    for (line, fault) in golden.lines().zip(all) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let number: u8 = words[0].parse().unwrap();
        let mut figures = Figures {
            number,
            ..Figures::default()
        };
        for (slot, word) in figures.details.iter_mut().zip(&words[1..1 + DETAILS]) {
            *slot = word.parse().unwrap();
        }
        let values = &words[1 + DETAILS..1 + DETAILS + VALUES];
        for (slot, word) in figures.values.iter_mut().zip(values) {
            *slot = u32::from_str_radix(word, 16).unwrap();
        }
        let sentence = words[1 + DETAILS + VALUES..].join(" ");
        let read = Fault::from_figures(&figures).map(|f| f.to_string());
        assert_eq!(read.as_deref(), Some(sentence.as_str()), "{line}");
        assert_eq!(fault.figures(), figures, "{fault:?}");
    }
}
