//! The bytes of every flash and wire layout (tables, images, saved settings, the fault log,
//! the telemetry stream, the link): CRC-32, little-endian reads, which of two sequence
//! numbers is newer, and a writer that cuts. A leaf: it imports nothing of the crate.

use core::fmt;

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), bit by bit: no lookup table in flash.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

/// The four bytes at `offset` (zeros past the end: callers check the length first). With
/// `u16_at`, `u32_at` and `f32_at`: the little-endian reads of every flash layout (tables,
/// images, saved settings).
fn word_at(bytes: &[u8], offset: usize) -> [u8; 4] {
    let mut word = [0u8; 4];
    if let Some(src) = bytes.get(offset..offset.saturating_add(4)) {
        word.copy_from_slice(src);
    }
    word
}

pub fn f32_at(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes(word_at(bytes, offset))
}

pub fn u32_at(bytes: &[u8], offset: usize) -> u32 {
    u32::from_le_bytes(word_at(bytes, offset))
}

/// The two bytes at `offset` (zero past the end).
pub fn u16_at(bytes: &[u8], offset: usize) -> u16 {
    let mut half = [0u8; 2];
    if let Some(src) = bytes.get(offset..offset.saturating_add(2)) {
        half.copy_from_slice(src);
    }
    u16::from_le_bytes(half)
}

/// Whether sequence number `a` is newer than `b`, wrapping (a saved record's, a log
/// entry's: one a second for 68 years before it matters).
pub fn newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

/// Bytes into a slice from the front, the rest dropped (a `fmt::Write` that cuts, never
/// fails: words longer than the room are cut at a character's boundary).
pub(crate) struct Put<'a>(pub(crate) &'a mut [u8], pub(crate) usize);

impl Put<'_> {
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Some(slot) = self.0.get_mut(self.1) {
                *slot = b;
                self.1 += 1;
            }
        }
    }
}

impl fmt::Write for Put<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = self.0.len().saturating_sub(self.1);
        let mut n = s.len().min(room);
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        self.bytes(s.as_bytes().get(..n).unwrap_or(&[]));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The standard check value of CRC-32/ISO-HDLC: "123456789" → 0xCBF43926.
    #[test]
    fn crc_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }
}
