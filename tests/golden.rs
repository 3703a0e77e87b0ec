//! Golden files: a saved-settings record and a configuration image as the firmware of
//! 2026-12-05 wrote them (settings blob version 1, image layout 3, both keeping each setting
//! at its place in the list of the time), committed before their layouts changed. Every
//! later firmware must read them with every value: an operator's saved settings and the
//! images already flashed survive an update. `GOLDEN_WRITE=1 cargo test --test golden --
//! --ignored` wrote them (the writers of the day); the values are written out here by hand.
#![cfg(feature = "storage")]

mod common;

use std::path::PathBuf;

use de_resonator::acquire::FrontEnd;
use de_resonator::controller::SettingSet;
use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};
use de_resonator::image::{self, AmplifierSpec, Image, PowerUp, DAC_BITS};
use de_resonator::store;
use de_resonator::{Setting, Settings, REFERENCE_DEVICE};

/// Every setting of the day by its key, each away from its default and from the others.
const VALUES: [(&str, f32); 21] = [
    ("target_hz", 43.5),
    ("margin", 0.07),
    ("slew_volts_per_second", 8000.0),
    ("tick_hz", 2000.0),
    ("settle_seconds", 0.3),
    ("ac_volts", 40.0),
    ("ac_hz", 43.0),
    ("check_seconds", 0.75),
    ("agreement", 2e-4),
    ("amplifier_tolerance_volts", 150.0),
    ("stuck_samples", 120.0),
    ("trim_tolerance", 2e-3),
    ("trim_window_seconds", 0.6),
    ("trim_pulse_volts", 180.0),
    ("trim_probe_fraction", 0.6),
    ("trim_every_seconds", 2.5),
    ("leakage_floor_ohms", 2e10),
    ("leakage_fall_per_second", 0.8),
    ("track_seconds", 0.4),
    ("probe_volts", 15.0),
    ("probe_hz", 400.0),
];

/// The RAM flash of the firmware's QEMU stand-in: two pages, a slot each.
const PAGES: usize = 2;

fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name)
}

fn settings() -> Settings {
    let mut s = Settings::for_target(0.0);
    for (key, value) in VALUES {
        let setting = Setting::from_key(key).unwrap_or_else(|| panic!("no setting {key}"));
        s.set(setting, value);
    }
    s
}

/// The settings declared after the day (not in `VALUES`): an older record or image lacks
/// them, and says so.
fn added_since() -> SettingSet {
    Setting::ALL
        .into_iter()
        .filter(|s| VALUES.iter().all(|(key, _)| *key != s.key()))
        .fold(SettingSet::EMPTY, SettingSet::with)
}

fn assert_every_value(what: &str, s: &Settings) {
    for (key, value) in VALUES {
        let setting = Setting::from_key(key).unwrap_or_else(|| panic!("no setting {key}"));
        assert_eq!(s.get(setting), value, "{what}: {key}");
    }
}

fn amplifier() -> AmplifierSpec {
    AmplifierSpec {
        dac_reference_volts: 2.5,
        gain: 4000.0,
        rail_volts: 10_000.0,
        dac_bits: DAC_BITS,
    }
}

/// The record as a slot holds it: the first bytes of the flash after a `save` (the rest of
/// the slot erased).
const RECORD: &str = "settings-record-v1.bin";
const IMAGE: &str = "image-v3.bin";

#[test]
#[ignore = "writes the golden files (GOLDEN_WRITE=1): done once, with the writers of the day"]
fn write_the_golden_files() {
    if std::env::var_os("GOLDEN_WRITE").is_none() {
        return;
    }
    // Written once: a golden file made again by later writers would test them against
    // themselves.
    for name in [RECORD, IMAGE] {
        assert!(
            !golden(name).exists(),
            "{name} exists: the golden files are the layouts of their day, never written again"
        );
    }
    let mut flash = vec![0xFF; PAGES * RAM_PAGE_BYTES];
    let range = 0..flash.len() as u32;
    store::save(RamFlash::new(&mut flash), range, &settings()).unwrap();
    let used = flash.iter().rposition(|b| *b != 0xFF).unwrap() + 1;
    std::fs::write(golden(RECORD), &flash[..used]).unwrap();
    let table = common::made_table(REFERENCE_DEVICE, 0.05, 16);
    let mut out = vec![0; image::image_bytes(table.len())];
    Image::write(
        &mut out,
        &REFERENCE_DEVICE.cast(),
        &amplifier(),
        &FrontEnd::NONE,
        &settings(),
        PowerUp::Wait,
        &table,
    )
    .unwrap();
    std::fs::write(golden(IMAGE), &out).unwrap();
}

/// The saved record of 2026-12-05 loads with every value.
#[test]
fn the_saved_settings_of_2026_12_05_load_with_every_value() {
    let record = std::fs::read(golden(RECORD)).unwrap();
    let mut flash = vec![0xFF; PAGES * RAM_PAGE_BYTES];
    flash[..record.len()].copy_from_slice(&record);
    let range = 0..flash.len() as u32;
    let loaded = store::load(RamFlash::new(&mut flash), range)
        .unwrap()
        .expect("a record");
    let (settings, new) = loaded.onto(Settings::for_target(0.0));
    assert_every_value(RECORD, &settings);
    assert_eq!(
        new,
        added_since(),
        "the settings added since the day, and only they, new"
    );
}

/// The image of 2026-12-05 parses with every value: the device, the amplifier, the power-up
/// choice and every default setting.
#[test]
fn the_image_of_2026_12_05_parses_with_every_value() {
    let bytes = std::fs::read(golden(IMAGE)).unwrap();
    let image = Image::parse(&bytes).unwrap();
    assert_eq!(image.params, REFERENCE_DEVICE.cast());
    assert_eq!(image.amplifier, amplifier());
    assert_eq!(image.power_up, PowerUp::Wait);
    assert_eq!(image.front_end, FrontEnd::NONE);
    assert_every_value(IMAGE, &image.settings);
    assert_eq!(
        image.defaulted,
        added_since(),
        "defaulted: the settings added since"
    );
    for setting in added_since().iter() {
        assert_eq!(
            image.settings.get(setting),
            setting.default_value(),
            "{setting:?}"
        );
    }
}
