//! The tuning table on the host: its layout, its lookup, and every corruption the firmware
//! must refuse (CRC, values, order, another device's, a wrong but sealed one).

mod common;

use common::{amplifier, reference_table};

use common::reseal;

use de_resonator::table::{self, Table, TableError};
use de_resonator::{Controller, Device, Fault, Settings, Tuner, REFERENCE_DEVICE};

#[test]
fn table_interpolation_is_exact_where_bias_squared_is_linear_in_f() {
    // Φ² = 1e6·(50 − f): the layout's interpolation reproduces it between points.
    let points: Vec<(f32, f32)> = (0..5)
        .map(|k| {
            let f = 50.0 - k as f32;
            (f, (1e6 * (50.0 - f)).sqrt())
        })
        .collect();
    let mut bytes = vec![0u8; table::table_bytes(5)];
    table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 0.0, &points).unwrap();
    let t = Table::parse(&bytes).unwrap();
    for f in [49.5f32, 48.25, 46.1, 50.0, 46.0] {
        let expected = (1e6 * (50.0 - f64::from(f))).sqrt();
        let got = f64::from(t.bias_volts(f).unwrap());
        assert!(
            (got - expected).abs() < 1e-5 * 2000.0,
            "{f}: {got} vs {expected}"
        );
    }
    assert_eq!(t.range_hz(), (46.0, 50.0));
    assert_eq!(t.params(), REFERENCE_DEVICE.cast());
}

/// Issue 12.5. A device whose f first falls, then rises past f0 (model.md §5): its table is
/// made (the turning point is one of its points) and its range is the tunable range (less
/// the headroom at the top); for targets across it the table's bias lies on the piece
/// `tune` takes (the smallest bias: below the minimum's bias while f0 is not passed) and
/// gives the target within 1e-4 in the f64 model.
#[test]
fn a_table_for_a_device_whose_frequency_turns_picks_the_smallest_bias() {
    let p = common::non_monotone_device();
    let tuner = Tuner::new(Device::new(p).unwrap());
    let bytes = common::made_table(p, 0.05, 64);
    let t = Table::parse(&bytes).unwrap();
    let range = tuner.tunable_range(0.05).unwrap();
    let f0 = tuner.zero_bias().natural_frequency_hz;
    let mut turns = Vec::new();
    tuner
        .for_each_turning_point(0.05, |e| turns.push(e))
        .unwrap();
    assert_eq!(turns.len(), 1);
    let minimum = turns[0];
    let (low, high) = t.range_hz();
    assert!((f64::from(low) / range.low_hz - 1.0).abs() < 1e-6, "{low}");
    assert!(f64::from(high) <= range.high_hz && f64::from(high) > f0);
    let d = tuner.device();
    for k in 1..200 {
        let target = f64::from(low) + (f64::from(high) - f64::from(low)) * f64::from(k) / 200.0;
        let volts = f64::from(t.bias_volts(target as f32).unwrap());
        let tuned = tuner.tune(target, 0.05).unwrap();
        if target < f0 {
            assert!(tuned.volts <= minimum.volts);
            assert!(volts <= minimum.volts * (1.0 + 1e-6), "{target}: {volts}");
        } else {
            assert!(volts > minimum.volts, "{target}: {volts}");
        }
        let offset = d.offset_for_bias(volts, tuner.limit().at.offset).unwrap();
        let error = (d.natural_frequency_hz_at(offset) / target - 1.0).abs();
        assert!(error < 1e-4, "{target}: {error}");
    }
}

/// Issue 12.5. A table whose frequency first rises, then falls (no device in 20,000 random
/// ones did that inside its safe region, so this one is made by hand): f = 50 − (Φ²/P − 1)²
/// with P = 10⁷ V², its peak as a point. The lookup takes the smallest bias, the root below
/// the peak, Φ² = P·(1 − √(50 − f)), while f is above f(0) = 49, and the falling side's
/// Φ² = P·(1 + √(50 − f)) below it, each within the interpolation's error.
#[test]
fn a_table_that_rises_then_falls_looks_up_the_smallest_bias() {
    let peak = 1e7f64;
    let f = |squared: f64| 50.0 - (squared / peak - 1.0).powi(2);
    let points: Vec<(f32, f32)> = (0..=40)
        .map(|k| {
            let squared = 2.5 * peak * f64::from(k) / 40.0;
            (f(squared) as f32, squared.sqrt() as f32)
        })
        .collect();
    let mut bytes = vec![0u8; table::table_bytes(points.len())];
    table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 0.0, &points).unwrap();
    let t = Table::parse(&bytes).unwrap();
    assert_eq!(t.range_hz(), (f(2.5 * peak) as f32, 50.0));
    for k in 1..100 {
        let target = 47.8 + 2.2 * f64::from(k) / 100.0;
        let got = f64::from(t.bias_volts(target as f32).unwrap()).powi(2) / peak;
        let root = (50.0 - target).sqrt();
        let expected = if target > 49.0 {
            1.0 - root
        } else {
            1.0 + root
        };
        assert!(
            (got - expected).abs() < 0.02,
            "{target}: {got} vs {expected}"
        );
    }
}

/// A frequency column that turns more often than any device's f(Φ) (`MAX_TURNS`) is
/// corruption, even resealed.
#[test]
fn a_table_whose_frequency_zigzags_is_refused() {
    let points: Vec<(f32, f32)> = (0..12)
        .map(|k| (45.0 + (k % 2) as f32, 100.0 * (k + 1) as f32))
        .collect();
    let mut bytes = vec![0u8; table::table_bytes(points.len())];
    let written = table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 0.0, &points);
    assert_eq!(
        written,
        Err(TableError::NotMonotone {
            index: table::MAX_TURNS as u16 + 2
        })
    );
}

/// The layout as documented: 68 header bytes, 8 a point, a 4-byte CRC; what is written is
/// read back, point by point and field by field.
#[test]
fn the_table_layout_is_the_documented_one() {
    for n in [2usize, 64, 1024] {
        assert_eq!(table::table_bytes(n), 68 + 8 * n + 4);
    }
    let device = Device::new(REFERENCE_DEVICE).unwrap();
    let top = Tuner::new(device).max_bias(0.1).unwrap();
    let mut points = vec![(0.0f32, 0.0f32); 2];
    table::fill(&device, &top, &[], &mut points).unwrap();
    assert_eq!(points[1].1, top.volts as f32);
    let mut one = vec![(0.0f32, 0.0f32); 1];
    assert!(table::fill(&device, &top, &[], &mut one).is_err());
    let mut bytes = vec![0u8; table::table_bytes(2)];
    table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 2.5e-6, &points).unwrap();
    let t = Table::parse(&bytes).unwrap();
    assert_eq!(t.points(), 2);
    assert_eq!((t.point(0), t.point(1)), (points[0], points[1]));
    assert_eq!((t.margin(), t.interpolation_error()), (0.05, 2.5e-6));
    assert_eq!(t.max_volts(), points[1].1);
    // Exactly a header and a CRC, no points: a count problem, not too short.
    let mut empty = vec![0u8; table::table_bytes(0)];
    empty[..4].copy_from_slice(b"DERT");
    empty[4..6].copy_from_slice(&table::VERSION.to_le_bytes());
    assert_eq!(
        Table::parse(&empty),
        Err(TableError::BadCount { points: 0 })
    );
}

/// Values that are no value, resealed so only the value checks can catch them: infinite,
/// zero where a value must be positive, negative where zero is allowed, a margin of exactly
/// 1; in the header and in the points.
#[test]
fn resealed_nonsense_values_are_refused_where_they_are() {
    let good = reference_table();
    let put = |at: usize, v: f32| {
        let mut bytes = good.clone();
        bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
        reseal(&mut bytes);
        Table::parse(&bytes).map(|_| ())
    };
    let header = |k: usize| 8 + 4 * k;
    let hz = |k: usize| table::HEADER_BYTES + table::POINT_BYTES * k;
    for (at, v, index) in [
        (header(0), f32::INFINITY, 0u16),
        (header(0), 0.0, 0),
        (header(4), -1.0, 4),
        (header(12), -1.0, 12),
        (header(1), f32::NEG_INFINITY, 1),
        (header(13), 1.0, 13),
        (hz(3), f32::INFINITY, 3),
        (hz(3), 0.0, 3),
        (hz(3) + 4, -1.0, 3),
        (hz(5) + 4, f32::INFINITY, 5),
    ] {
        assert_eq!(put(at, v), Err(TableError::NotFinite { index }), "{at} {v}");
    }
    // Zero where zero is allowed: damping, and a table error of 0.
    assert!(put(header(12), 0.0).is_ok());
    assert!(put(header(14), 0.0).is_ok());
}

/// The frequency may turn up to `MAX_TURNS` times (f(Φ) is not monotone on every device),
/// not once more; the bias must rise strictly.
#[test]
fn a_table_turns_at_most_its_limit() {
    let zigzag = |turns: usize| -> Vec<(f32, f32)> {
        (0..turns + 2)
            .map(|k| (45.0 + (k % 2) as f32, 100.0 * (k + 1) as f32))
            .collect()
    };
    let write = |points: &[(f32, f32)]| {
        let mut bytes = vec![0u8; table::table_bytes(points.len())];
        table::write(&mut bytes, &REFERENCE_DEVICE.cast(), 0.05, 0.0, points).map(|_| ())
    };
    assert_eq!(write(&zigzag(table::MAX_TURNS)), Ok(()));
    assert!(write(&zigzag(table::MAX_TURNS + 1)).is_err());
    let flat_bias = [(45.0f32, 100.0f32), (44.0, 100.0)];
    assert_eq!(write(&flat_bias), Err(TableError::NotMonotone { index: 1 }));
}

/// A table that is consistent but wrong (its bias column scaled by 0.99, resealed) passes every
/// check of its own, and the direct solve refuses it: the natural frequency at the table's
/// bias is more than the 1e-4 agreement off the solve's (8.4e-4 here).
#[test]
fn a_wrong_but_sealed_table_disagrees_with_the_solve() {
    let mut bytes = reference_table();
    let points = (bytes.len() - table::HEADER_BYTES - 4) / table::POINT_BYTES;
    for k in 0..points {
        let at = table::HEADER_BYTES + table::POINT_BYTES * k + 4;
        let v = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) * 0.99;
        bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }
    reseal(&mut bytes);
    assert!(Table::parse(&bytes).is_ok());
    let params = REFERENCE_DEVICE.cast::<f32>();
    let fault = Controller::start(params, &bytes, amplifier(), Settings::for_target(44.0));
    match fault {
        Err(Fault::Disagree {
            table_hz,
            solved_hz,
            ..
        }) => assert!(
            (table_hz / solved_hz - 1.0).abs() > 1e-4,
            "{table_hz} {solved_hz}"
        ),
        other => panic!("{other:?}"),
    }
}

/// Every table error reads as one sentence with its numbers.
#[test]
fn table_errors_read_as_sentences() {
    let cases: [(TableError, &str); 6] = [
        (
            TableError::TooShort { bytes: 10 },
            "table of 10 bytes is too short",
        ),
        (TableError::BadMagic, "not a tuning table (no DERT magic)"),
        (
            TableError::BadCount { points: 1 },
            "table has 1 points, expected 2 to 1024",
        ),
        (
            TableError::WrongLength {
                expected: 584,
                bytes: 583,
            },
            "table is 583 bytes, its count says 584",
        ),
        (
            TableError::OtherDevice {
                field: de_resonator::Field::Thickness,
            },
            "table was made for another device (`thickness` differs)",
        ),
        (
            TableError::NotFinite { index: 3 },
            "table value 3 is NaN, infinite or not positive",
        ),
    ];
    for (error, text) in cases {
        assert_eq!(error.to_string(), text);
    }
}

#[test]
fn corrupted_tables_are_refused_with_the_reason() {
    let good = reference_table();
    assert!(Table::parse(&good).is_ok());

    let mut flipped = good.clone();
    flipped[100] ^= 0x01;
    assert!(matches!(
        Table::parse(&flipped),
        Err(TableError::BadCrc { .. })
    ));

    assert!(matches!(
        Table::parse(&good[..good.len() - 1]),
        Err(TableError::WrongLength { .. })
    ));
    assert!(matches!(
        Table::parse(&good[..10]),
        Err(TableError::TooShort { bytes: 10 })
    ));
    assert!(matches!(
        Table::parse(&[]),
        Err(TableError::TooShort { bytes: 0 })
    ));

    let mut magic = good.clone();
    magic[0] = b'X';
    assert_eq!(Table::parse(&magic), Err(TableError::BadMagic));

    // A NaN bias in point 5, correctly sealed: only the value check can catch it.
    let mut nan = good.clone();
    let at = table::HEADER_BYTES + table::POINT_BYTES * 5 + 4;
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    reseal(&mut nan);
    assert_eq!(Table::parse(&nan), Err(TableError::NotFinite { index: 5 }));

    // Points 7 and 8 swapped, sealed: not monotone at 8.
    let mut swapped = good.clone();
    let p7 = table::HEADER_BYTES + table::POINT_BYTES * 7;
    let (a, b) = (p7, p7 + table::POINT_BYTES);
    let seven: Vec<u8> = swapped[a..b].to_vec();
    swapped.copy_within(b..b + table::POINT_BYTES, a);
    swapped[b..b + table::POINT_BYTES].copy_from_slice(&seven);
    reseal(&mut swapped);
    assert_eq!(
        Table::parse(&swapped),
        Err(TableError::NotMonotone { index: 8 })
    );

    // A count that does not match the length.
    let mut count = good.clone();
    count[6] = 63;
    reseal(&mut count);
    assert!(matches!(
        Table::parse(&count),
        Err(TableError::WrongLength { .. })
    ));
}

#[test]
fn the_controller_refuses_a_bad_table_and_a_table_for_another_device() {
    let params = REFERENCE_DEVICE.cast::<f32>();
    let settings = Settings::for_target(44.0);
    let mut bad = reference_table();
    bad[200] ^= 0x80;
    let fault = Controller::start(params, &bad, amplifier(), settings).unwrap_err();
    assert!(
        matches!(fault, Fault::Table(TableError::BadCrc { .. })),
        "{fault}"
    );

    let other = de_resonator::DeviceParams {
        shear_modulus: 46e3,
        ..params
    };
    let fault = Controller::start(other, &reference_table(), amplifier(), settings).unwrap_err();
    assert_eq!(
        fault,
        Fault::Table(TableError::OtherDevice {
            field: de_resonator::Field::ShearModulus
        })
    );
}

/// A batch's table (version 2, model.md §10): its ranges and guaranteed limit read back; a
/// range that does not hold the device's value, or a limit not a positive number, sealed
/// with a fresh CRC, is refused naming the field; version 1 is what a device alone gets.
#[test]
fn a_batch_table_keeps_its_ranges_and_limit() {
    let b = common::reference_batch();
    let (bytes, g) = common::made_batch_table(&b, 0.05, 32, 4096).unwrap();
    assert_eq!(bytes.len(), table::batch_table_bytes(32));
    let t = Table::parse(&bytes).unwrap();
    let batch = t.batch().unwrap();
    assert!(f64::from(batch.low.shear_modulus) <= 40.5e3);
    assert!(f64::from(batch.high.shear_modulus) >= 49.5e3);
    assert_eq!(
        (batch.low.breakdown_field, batch.high.breakdown_field),
        (35e6, 200e6)
    );
    assert!(f64::from(batch.limit_volts) <= g && f64::from(batch.limit_volts) > g * (1.0 - 1e-7));
    // Its top: (1 − margin)(1 − headroom) of the guaranteed limit, well below the device's.
    let top = f64::from(t.max_volts());
    assert!(
        (top / (0.95 * (1.0 - table::HEADROOM) * g) - 1.0).abs() < 1e-6,
        "{top} {g}"
    );
    assert_eq!(
        Table::parse(&common::made_table(REFERENCE_DEVICE, 0.05, 32))
            .unwrap()
            .batch(),
        None
    );
    let field_at = |k: usize| table::HEADER_BYTES + 4 * k;
    for (at, value, says) in [
        (field_at(0), 50e3f32, "shear_modulus"), // low above the device's 45 kPa
        (field_at(13 + 4), 90e6, "breakdown_field"), // high below the device's 100 MV/m
        (field_at(26), f32::NAN, "guaranteed limit"),
        (field_at(26), -1.0, "guaranteed limit"),
    ] {
        let mut bad = bytes.clone();
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        reseal(&mut bad);
        let e = Table::parse(&bad).unwrap_err();
        assert!(matches!(e, TableError::BadBatch { .. }), "{e}");
        assert!(e.to_string().contains(says), "{e}");
    }
    // The capacitance bands: from 0 V to the top, each holding the reference device's own
    // C there (from its geometry, model.md §8); any device's C between two biases lies
    // between the lower's low and the upper's high.
    let bands = batch.capacitance;
    assert_eq!(bands.0[0].volts, 0.0);
    assert!(bands.0[table::BATCH_BIASES - 1].volts >= t.max_volts());
    let d = de_resonator::Device::new(REFERENCE_DEVICE).unwrap();
    let c = |volts: f64| {
        let stretch = de_resonator::Limit::of(&d)
            .stretch_for_bias(&d, volts)
            .unwrap();
        let p = REFERENCE_DEVICE;
        let area = p.length_active * stretch * p.width * p.prestretch_2;
        8.8541878128e-12 * p.relative_permittivity * area * stretch * p.prestretch_2 / p.thickness
    };
    for k in 0..=100 {
        let volts = t.max_volts() * k as f32 / 100.0;
        let (low, high) = bands.farads_at(volts).unwrap();
        let own = c(f64::from(volts));
        assert!(
            f64::from(low) <= own && own <= f64::from(high),
            "{low} {own} {high}"
        );
    }
    assert_eq!(
        bands.farads_at(1.01 * bands.0[table::BATCH_BIASES - 1].volts),
        None
    );
    let band_at = |j: usize, word: usize| field_at(27 + 3 * j + word);
    let last = table::BATCH_BIASES - 1;
    // Above the band before it, below the table's top.
    let below_top = 0.5 * (bands.0[last - 1].volts + t.max_volts());
    for (at, value) in [
        (band_at(0, 0), 1.0f32),        // the first bias not 0 V
        (band_at(5, 0), 0.0),           // a bias not rising
        (band_at(3, 1), -1e-10),        // a low not positive
        (band_at(3, 2), 1e-13),         // a high below its low
        (band_at(9, 2), f32::INFINITY), // a high not finite
        (band_at(last, 0), below_top),  // the last below the top
    ] {
        let mut bad = bytes.clone();
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        reseal(&mut bad);
        let e = Table::parse(&bad).unwrap_err();
        assert!(matches!(e, TableError::BadCapacitance { .. }), "{at}: {e}");
        assert!(e.to_string().contains("capacitance"), "{e}");
    }
}
