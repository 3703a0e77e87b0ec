//! Settings saved in flash (the `storage` feature): two slots, each a whole number of
//! flash pages, holding one record each: a magic, a sequence number, the settings blob and a
//! CRC-32. `save` erases the slot that does not hold the newest valid record and writes the
//! next sequence number there, the CRC last; `load` takes the newest valid record. A power cut
//! anywhere in a save leaves the other slot, the last good settings, as it was. On the flash
//! layer ([`crate::flash`]): embedded-storage's `NorFlash`, the STM32F4's flash
//! controller on the chip, `RamFlash` in QEMU and in tests (which can fail or tear a write at
//! any byte).
//!
//! sequential-storage (a map, each write a new item) was built and measured first: it passed
//! the same power-cut tests, and took 5,976 B more of the firmware's flash than this store
//! when last measured (BENCHMARKS.md, "Flash of our number parser, number writer and settings
//! store").
//!
//! The blob is versioned: version (u16), the number of settings (u16), then each setting by
//! its stable id (`Setting::id`): id (u16), two zero bytes, value (f32; 0 = off where it can
//! be). A firmware that adds a setting reads an older blob with every value it holds, the
//! new one at the image's value (the board says which); a blob holding a setting this
//! firmware does not know (saved by a newer one) is refused by name, as is one of a version
//! it does not read that has this version's length; one of another length cannot be told
//! from a record torn by a power cut, and is passed over as one is. Version 1 (until
//! 2026-12-05) kept the settings by place, which was their id: read as such. Whether the
//! settings are in range is the controller's boot check, as for any settings.

use core::fmt;
use core::ops::Range;

use embedded_storage::nor_flash::{NorFlash, NorFlashError};

use crate::bytes::{crc32, f32_at, newer, u16_at, u32_at};
use crate::controller::{Held, Setting, Settings};
use crate::flash::{halves, FlashKind};

/// The blob's layout version this code writes (it reads 1 too).
pub const BLOB_VERSION: u16 = 2;
const COUNT: usize = Setting::ALL.len();
/// Bytes a setting takes in a blob: id, two zero bytes, value.
const ENTRY_BYTES: usize = 8;
/// The blob's length in bytes.
pub const BLOB_BYTES: usize = 4 + ENTRY_BYTES * COUNT;
/// The most settings a blob this code reads may hold (a newer firmware's, refused by name
/// if it holds one unknown here): the ids a `SettingSet` has room for.
const MAX_HELD: usize = 32;
/// A record's first bytes.
const MAGIC: [u8; 4] = *b"DERS";
/// A record: magic, sequence number (u32), blob, CRC-32 of all before it (u32).
const RECORD_BYTES: usize = 8 + BLOB_BYTES + 4;
/// The longest record read: a blob of `MAX_HELD` settings.
const MAX_RECORD_BYTES: usize = 8 + 4 + ENTRY_BYTES * MAX_HELD + 4;
/// Where the CRC starts in a record.
const CRC_AT: usize = RECORD_BYTES - 4;

/// Why settings could not be saved or read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError {
    /// The flash failed (a write or erase not aligned, out of its bounds, or failing).
    Flash(FlashKind),
    /// The range is not two slots of whole pages, each room for a record.
    Range,
    /// The newest record holds a blob of a layout version this code does not read (or of
    /// a wrong length): refused, never read as this one.
    Version { version: u16, count: u16 },
    /// The newest record holds a setting this firmware does not know (saved by a newer
    /// one): refused, so that nothing it asked for is silently dropped.
    UnknownSetting { id: u16 },
    /// The fault log's half is full and its next entry needs the other erased, which is not
    /// done while running on a chip (an erase stalls it past its watchdog): at the next boot.
    LogFull,
}

impl fmt::Display for StoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            StoreError::Flash(kind) => write!(f, "flash error: {kind:?}"),
            StoreError::Range => {
                write!(
                    f,
                    "the settings flash range is not two slots of whole pages"
                )
            }
            StoreError::LogFull => write!(
                f,
                "the fault log is full for this run (its other half is erased at the next \
                 boot): entry not kept"
            ),
            StoreError::Version { version, count } => write!(
                f,
                "saved settings of layout version {version} ({count} settings): this firmware \
                 reads versions 1 and {BLOB_VERSION}; ignored"
            ),
            StoreError::UnknownSetting { id } => write!(
                f,
                "saved settings hold setting id {id}, which this firmware does not know (saved \
                 by a newer firmware); ignored: `save` again to keep this firmware's"
            ),
        }
    }
}

impl StoreError {
    /// The flash's own failure, by its kind.
    pub fn flash<E: NorFlashError>(e: E) -> Self {
        StoreError::Flash(e.kind().into())
    }
}

/// The settings as a blob, each by its id.
#[inline]
pub fn encode(settings: &Settings) -> [u8; BLOB_BYTES] {
    let mut blob = [0u8; BLOB_BYTES];
    let head = BLOB_VERSION
        .to_le_bytes()
        .into_iter()
        .chain((COUNT as u16).to_le_bytes());
    let entries = Setting::ALL.into_iter().flat_map(|s| {
        let (id, value) = (
            u16::from(s.id()).to_le_bytes(),
            settings.get(s).to_le_bytes(),
        );
        [id[0], id[1], 0, 0, value[0], value[1], value[2], value[3]]
    });
    for (slot, byte) in blob.iter_mut().zip(head.chain(entries)) {
        *slot = byte;
    }
    blob
}

/// The blob's length from its first four bytes (version and count); `None` for a version
/// this code does not read or a count beyond `MAX_HELD`.
fn blob_len(version: u16, count: u16) -> Option<usize> {
    let count = usize::from(count);
    match version {
        _ if count > MAX_HELD => None,
        1 => Some(4 + 4 * count),
        BLOB_VERSION => Some(4 + ENTRY_BYTES * count),
        _ => None,
    }
}

/// A blob's settings, by id (version 2) or by place (version 1, whose places were the ids).
pub fn decode(blob: &[u8]) -> Result<Held, StoreError> {
    let (version, count) = (u16_at(blob, 0), u16_at(blob, 2));
    if blob_len(version, count) != Some(blob.len()) {
        return Err(StoreError::Version { version, count });
    }
    let mut held = Held::NONE;
    for k in 0..usize::from(count) {
        let (id, value) = match version {
            1 => (k as u16, f32_at(blob, 4 + 4 * k)),
            _ => (
                u16_at(blob, 4 + ENTRY_BYTES * k),
                f32_at(blob, 4 + ENTRY_BYTES * k + 4),
            ),
        };
        let setting = u8::try_from(id)
            .ok()
            .and_then(Setting::from_id)
            .ok_or(StoreError::UnknownSetting { id })?;
        held = held.with(setting, value);
    }
    Ok(held)
}

/// The two slots' first offsets, checked against the flash's pages.
fn slots<F: NorFlash>(range: &Range<u32>) -> Result<[u32; 2], StoreError> {
    let (starts, half) = halves::<F>(range).ok_or(StoreError::Range)?;
    // Room for the longest record read (`read_slot` reads up to it), not only this one's.
    if half < MAX_RECORD_BYTES.next_multiple_of(F::WRITE_SIZE.max(1)) {
        return Err(StoreError::Range);
    }
    Ok(starts)
}

/// The valid record in a slot, read into `record`: its sequence number and its blob's
/// length (any version's, up to `MAX_HELD` settings: its version is `decode`'s to read or
/// refuse; the blob at `record[8..8 + length]`).
fn read_slot<F: NorFlash>(
    flash: &mut F,
    at: u32,
    record: &mut [u8; MAX_RECORD_BYTES],
) -> Result<Option<(u32, usize)>, StoreError> {
    flash
        .read(at, record.get_mut(..12).unwrap_or(&mut []))
        .map_err(StoreError::flash)?;
    if record.get(..4) != Some(&MAGIC[..]) {
        return Ok(None);
    }
    // A version or count this code cannot size (a newer firmware's layout): its CRC is
    // checked at this version's length, so a record of that length is refused by name
    // (`decode`); one of another length cannot be told from a torn one and is passed over,
    // as a save cut by a power cut is (the other slot's settings, or the image's, boot).
    let len = blob_len(u16_at(record, 8), u16_at(record, 10)).unwrap_or(BLOB_BYTES);
    let crc_at = 8 + len;
    let Some(whole) = record.get_mut(..crc_at + 4) else {
        return Ok(None);
    };
    flash.read(at, whole).map_err(StoreError::flash)?;
    let body = record.get(..crc_at).unwrap_or(&[]);
    if crc32(body) != u32_at(record, crc_at) {
        return Ok(None);
    }
    Ok(Some((u32_at(record, 4), len)))
}

/// The slot of the newest valid record and its sequence number.
fn newest<F: NorFlash>(
    flash: &mut F,
    range: &Range<u32>,
) -> Result<Option<(usize, u32)>, StoreError> {
    let starts = slots::<F>(range)?;
    let mut record = [0u8; MAX_RECORD_BYTES];
    let mut best: Option<(usize, u32)> = None;
    for (slot, &at) in starts.iter().enumerate() {
        if let Some((sequence, _)) = read_slot(flash, at, &mut record)? {
            if best.is_none_or(|(_, s)| newer(sequence, s)) {
                best = Some((slot, sequence));
            }
        }
    }
    Ok(best)
}

/// Save the settings.
pub fn save<F: NorFlash>(
    flash: F,
    range: Range<u32>,
    settings: &Settings,
) -> Result<(), StoreError> {
    save_blob(flash, range, &encode(settings))
}

/// Save a blob as it is (`save`'s work; a test writes another version's blob with it).
pub fn save_blob<F: NorFlash>(
    mut flash: F,
    range: Range<u32>,
    blob: &[u8; BLOB_BYTES],
) -> Result<(), StoreError> {
    let starts = slots::<F>(&range)?;
    let (slot, sequence) = match newest(&mut flash, &range)? {
        Some((slot, sequence)) => (1 - slot, sequence.wrapping_add(1)),
        None => (0, 1),
    };
    let at = starts.get(slot).copied().ok_or(StoreError::Range)?;
    let half = (range.end - range.start) / 2;
    flash.erase(at, at + half).map_err(StoreError::flash)?;
    // The body, then the CRC in a write of its own: a cut anywhere leaves a CRC that does
    // not match (the erased 0xFF…, or a part of it).
    let word = F::WRITE_SIZE.max(1);
    let mut record = [0xFFu8; RECORD_BYTES + 32];
    let body = MAGIC
        .into_iter()
        .chain(sequence.to_le_bytes())
        .chain(blob.iter().copied());
    for (slot, byte) in record.iter_mut().zip(body) {
        *slot = byte;
    }
    let crc = crc32(record.get(..CRC_AT).unwrap_or(&[]));
    let body_len = (CRC_AT / word) * word;
    let tail_len = (RECORD_BYTES - body_len).next_multiple_of(word);
    let (Some(head), true) = (record.get(..body_len), body_len + tail_len <= record.len()) else {
        return Err(StoreError::Range);
    };
    flash.write(at, head).map_err(StoreError::flash)?;
    for (slot, byte) in record.iter_mut().skip(CRC_AT).zip(crc.to_le_bytes()) {
        *slot = byte;
    }
    let tail = record.get(body_len..body_len + tail_len).unwrap_or(&[]);
    flash
        .write(at + body_len as u32, tail)
        .map_err(StoreError::flash)
}

/// The newest settings saved (`None`: none yet, or none that reads).
pub fn load<F: NorFlash>(mut flash: F, range: Range<u32>) -> Result<Option<Held>, StoreError> {
    let Some((slot, _)) = newest(&mut flash, &range)? else {
        return Ok(None);
    };
    let at = slots::<F>(&range)?
        .get(slot)
        .copied()
        .ok_or(StoreError::Range)?;
    let mut record = [0u8; MAX_RECORD_BYTES];
    match read_slot(&mut flash, at, &mut record)? {
        Some((_, len)) => decode(record.get(8..8 + len).unwrap_or(&[])).map(Some),
        None => Ok(None),
    }
}

/// Erase both slots (a user's reset of the saved settings).
pub fn erase<F: NorFlash>(mut flash: F, range: Range<u32>) -> Result<(), StoreError> {
    flash
        .erase(range.start, range.end)
        .map_err(StoreError::flash)
}
