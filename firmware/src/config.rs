//! The configuration image in its own flash sector (sector 11, `memory.x`'s CONFIG), read in
//! place: the device, the amplifier, the default settings and the table (the core's `image`
//! layout, written by `host-sim image`). Nothing about the device is compiled in.

use de_resonator::{Image, ImageError};

extern "C" {
    /// The sector's first byte and one past its last (memory.x).
    static _config_start: u8;
    static _config_end: u8;
}

/// The whole sector, as bytes (erased: 0xFF on silicon, 0x00 under QEMU).
pub fn sector() -> &'static [u8] {
    let start = core::ptr::addr_of!(_config_start);
    let end = core::ptr::addr_of!(_config_end);
    let len = (end as usize).saturating_sub(start as usize);
    // SAFETY: the linker reserves [start, end) as flash for the image only (memory.x); flash
    // is never written while the firmware runs, so a shared 'static view of it is sound.
    unsafe { core::slice::from_raw_parts(start, len) }
}

/// The image flashed, checked (magic, version, length, CRC, amplifier).
pub fn image() -> Result<Image<'static>, ImageError> {
    Image::parse(sector())
}
