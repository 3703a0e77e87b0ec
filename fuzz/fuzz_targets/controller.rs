//! Arbitrary settings and table bytes for the reference device, the table resealed with a
//! fresh CRC (so the fuzzer reaches the checks behind it): boot never panics, and a
//! controller that starts never commands below 0 V or above its cap, whatever it measures.
#![no_main]

use de_resonator::bytes::crc32;
use de_resonator::{Amplifier, Controller, Inputs, Settings, REFERENCE_DEVICE};
use libfuzzer_sys::fuzz_target;

/// The next f32 from the data (NaN when it runs out).
fn take(data: &mut &[u8]) -> f32 {
    match data.split_first_chunk::<4>() {
        Some((word, rest)) => {
            *data = rest;
            f32::from_le_bytes(*word)
        }
        None => f32::NAN,
    }
}

fuzz_target!(|data: &[u8]| {
    let mut data = data;
    let mut s = Settings::for_target(take(&mut data));
    s.margin = take(&mut data);
    s.slew_volts_per_second = take(&mut data);
    s.ac_volts = take(&mut data);
    s.ac_hz = take(&mut data);
    let trim = take(&mut data).abs().min(1e-2);
    s.trim_tolerance = (trim > 0.0).then_some(trim);
    let stretch = take(&mut data);
    let Ok(amplifier) = Amplifier::new(2.5, 4000.0) else {
        return;
    };
    let mut table = data.to_vec();
    if let Some(body) = table.len().checked_sub(4) {
        let crc = crc32(&table[..body]);
        table[body..].copy_from_slice(&crc.to_le_bytes());
    }
    let params = REFERENCE_DEVICE.cast::<f32>();
    let Ok((mut c, boot)) = Controller::start(params, &table, amplifier, s) else {
        return;
    };
    for k in 0..2000u32 {
        let inputs = if k % 7 == 0 {
            Inputs::stretch(stretch)
        } else {
            Inputs::NONE
        };
        let out = c.tick(inputs);
        assert!(out.volts >= 0.0 && out.volts <= boot.max_volts);
    }
});
