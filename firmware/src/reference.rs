//! The reference device (model.md §9), its table and the reference run, compiled in for the
//! on-target checks and counts only (`check`, `count`): the product (`firmware`) takes its
//! device from the configuration image, and nothing here is linked into it.

use de_resonator::{Amplifier, DeviceParams, Settings, REFERENCE_DEVICE};

/// The tuning table for the reference device, from `host-sim lut` (tables/reference.bin).
pub static TABLE: &[u8] = include_bytes!("../../tables/reference.bin");

/// The table of a batch about the reference device (model.md §10: μ ±10%, H ±5%, E_B 35–200
/// MV/m and more), from `host-sim lut --device devices/vhb-batch.toml`
/// (tables/vhb-batch.bin): 44.35 to 45.95 Hz under its guaranteed cap.
pub static BATCH_TABLE: &[u8] = include_bytes!("../../tables/vhb-batch.bin");

/// The reference device of model.md §9, in f32.
pub fn device() -> DeviceParams<f32> {
    REFERENCE_DEVICE.cast()
}

/// DAC8551 with a 2.5 V reference into an amplifier of gain 4000: 0 to 10 kV.
pub fn amplifier() -> Result<Amplifier, de_resonator::CodeError> {
    Amplifier::new(2.5, 4000.0)
}

/// The reference run: 44 Hz, then 100 V of AC at 40 Hz.
pub fn settings() -> Settings {
    Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    }
}
