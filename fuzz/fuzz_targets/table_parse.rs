//! Any bytes as a tuning table: parsing never panics, and a table that parses never gives a
//! bias outside its own points' [0, top] for any target, nor a NaN.
#![no_main]

use de_resonator::table::Table;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(table) = Table::parse(data) else {
        return;
    };
    let (low, high) = table.range_hz();
    assert!(low <= high);
    let top = table.max_volts();
    let _ = table.check_device(&table.params());
    // Targets: the range's ends and inside, and a value from the data itself.
    let tail = data.len().saturating_sub(8);
    let from_data = data
        .get(tail..tail + 4)
        .and_then(|b| b.try_into().ok())
        .map_or(f32::NAN, f32::from_le_bytes);
    for target in [low, high, 0.5 * (low + high), from_data, f32::NAN, -1.0] {
        if let Ok(volts) = table.bias_volts(target) {
            assert!(
                volts >= 0.0 && volts <= top,
                "{target} Hz gave {volts} V, top {top} V"
            );
        }
    }
});
