//! On-target checks: the f32 core on the chip against figures computed independently in
//! f64 on the host (the published figures of issue 2), and every bad input of the firmware
//! ending in a typed fault and 0 V (never a panic or a HardFault). Status 0 when all pass.
#![no_std]
#![no_main]

use de_resonator::table::TableError;
use de_resonator::{
    Controller, Dac8551, DacCode, Device, Event, Fault, Inputs, Settings, Tuner, REFERENCE_DEVICE,
};
use de_resonator_firmware::reference::{amplifier, device, settings, TABLE};
use de_resonator_firmware::{exit, stand_in::RecordingBus};

/// Largest table this check copies to corrupt.
const MAX_TABLE: usize = 1024;

fn check(name: &str, ok: bool, failures: &mut u32) {
    if ok {
        defmt::info!("pass  {=str}", name);
    } else {
        defmt::error!("FAIL  {=str}", name);
        *failures += 1;
    }
}

fn close(got: f32, expected: f64, relative: f64) -> bool {
    (f64::from(got) - expected).abs() <= relative * expected.abs()
}

fn start(table: &[u8], settings: Settings) -> Result<Controller, Fault> {
    let amp = amplifier().map_err(Fault::Amplifier)?;
    Controller::start(device(), table, amp, settings).map(|(c, _)| c)
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut failures = 0;
    let f = &mut failures;

    // The f32 core on the chip against the f64 figures (model.md §9 device, issue 2).
    match Device::new(REFERENCE_DEVICE.cast::<f32>()) {
        Ok(dev) => {
            let tuner = Tuner::new(dev);
            check(
                "f at zero bias 45.9527 Hz",
                close(tuner.zero_bias().natural_frequency_hz, 45.9527, 2e-6),
                f,
            );
            let limit = tuner.limit();
            check(
                "limit emi at 9854.73 V",
                close(limit.at.volts, 9854.73, 2e-6),
                f,
            );
            check(
                "limit stretch 2.36254",
                close(limit.at.stretch, 2.36254, 2e-6),
                f,
            );
            check(
                "f at the limit 42.7292 Hz",
                close(limit.at.natural_frequency_hz, 42.7292, 2e-6),
                f,
            );
            let tuned = tuner.tune(44.0, 0.0).map(|e| e.volts).unwrap_or(f32::NAN);
            check("44 Hz at 7449.88 V", close(tuned, 7449.88, 2e-6), f);
        }
        Err(_) => check("reference device valid", false, f),
    }

    // The flashed table and the boot of the reference run.
    check("table parses", de_resonator::Table::parse(TABLE).is_ok(), f);
    check("reference run boots", start(TABLE, settings()).is_ok(), f);

    // Bad input: each a typed fault, never a panic.
    let mut copy = [0u8; MAX_TABLE];
    let n = TABLE.len().min(MAX_TABLE);
    copy[..n].copy_from_slice(&TABLE[..n]);
    copy[100] ^= 0x10;
    let crc = start(&copy[..n], settings());
    check(
        "corrupted table: BadCrc",
        matches!(crc, Err(Fault::Table(TableError::BadCrc { .. }))),
        f,
    );
    let short = start(&TABLE[..20], settings());
    check(
        "truncated table: TooShort",
        matches!(short, Err(Fault::Table(TableError::TooShort { .. }))),
        f,
    );
    for target in [f32::NAN, f32::INFINITY, -1.0, 60.0] {
        let r = start(
            TABLE,
            Settings {
                target_hz: target,
                ..settings()
            },
        );
        check(
            "bad target: typed fault",
            matches!(r, Err(Fault::Table(_)) | Err(Fault::Tune(_))),
            f,
        );
    }
    let unsafe_params = de_resonator::DeviceParams {
        prestretch_1: 0.6,
        ..device()
    };
    let r = amplifier()
        .map_err(Fault::Amplifier)
        .and_then(|amp| Controller::start(unsafe_params, TABLE, amp, settings()));
    check(
        "device unsafe at zero bias: Device fault",
        matches!(r, Err(Fault::Device(_))),
        f,
    );

    // A DAC bus that fails on the 10th frame: the fault, then 0 V.
    if let Ok(mut c) = start(TABLE, settings()) {
        let mut dac = Dac8551::new(RecordingBus::new(Some(10)));
        let mut zeroed = false;
        for _ in 0..20 {
            let out = c.tick(Inputs::NONE);
            if dac.write(out.code).is_err() {
                let after = c.fault(Fault::Bus);
                zeroed = after.code == DacCode(0)
                    && matches!(after.event, Some(Event::Fault(Fault::Bus)))
                    && c.tick(Inputs::NONE).code == DacCode(0);
                break;
            }
        }
        check("DAC bus error: fault and 0 V", zeroed, f);
    }
    // A NaN sensor sample: the fault and 0 V.
    if let Ok(mut c) = start(TABLE, settings()) {
        c.tick(Inputs::NONE);
        let out = c.tick(Inputs::stretch(f32::NAN));
        check(
            "NaN sensor: fault and 0 V",
            out.code == DacCode(0) && matches!(out.event, Some(Event::Fault(Fault::Sensor { .. }))),
            f,
        );
    }

    if failures == 0 {
        defmt::info!("all on-target checks passed");
        exit(0)
    }
    defmt::error!("{=u32} on-target checks failed", failures);
    exit(1)
}
