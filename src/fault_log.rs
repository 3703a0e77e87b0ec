//! The fault log: the last faults the board met, kept in flash beside
//! the saved settings so that the reason of a trip outlives a reset or a power cut. Each
//! entry is the cause with its figures (`Fault::figures`: the fault's sentence is written
//! again from them, whole, with every figure in it), the board's tick and time since boot,
//! and the voltage, current and stretch when it came; a watchdog reset and a brown-out are
//! entries too.
//!
//! Two halves of whole flash pages, each room for at least `KEPT` entries. An entry is written
//! at the first erased slot of the half that holds the newest one, its CRC in a write of its
//! own after the rest: a power cut in an append leaves that entry unreadable (skipped) and
//! every other as it was. When that half is full, the other half is erased and the log goes on
//! there: the full half still holds the `KEPT` newest. `read` gives the valid entries, newest
//! first; `clear` erases both halves. Generic over embedded-storage's `NorFlash`, as the
//! settings' `store` is.
//!
//! The entries (always) and their flash (the `storage` feature). An entry ([`ENTRY_BYTES`],
//! little-endian):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 2 | magic `DG` |
//! | 2 | 1 | cause: `Fault::number` (1–24), 0xF0 a watchdog reset, 0xF1 a brown-out |
//! | 3 | 1 | 0: the fault's figures follow; 1: the cause says it all (a reset) |
//! | 4 | 4 | sequence number, u32 (from 1; the newest is the largest, wrapping) |
//! | 8 | 4 | the board's tick since boot, u32 |
//! | 12 | 4 | time since boot, s, f32 |
//! | 16 | 4 | the voltage commanded, V, f32 |
//! | 20 | 4 | the amplifier's current, A, f32 (NaN: not measured) |
//! | 24 | 4 | the stretch sample, f32 (NaN: not measured) |
//! | 28 | 4 | the figures' indices (`Figures::details`) |
//! | 32 | 28 | the figures' numbers, 7 × u32 (f32 as its bits) |
//! | 60 | 4 | CRC-32 (IEEE 802.3) of bytes 0–59 |
//!
//! An entry of the layout before (magic `DF`) is read as it was: its words, cut at 32 bytes,
//! at bytes 28–59 (their length at byte 3).

use core::fmt;
#[cfg(feature = "storage")]
use core::ops::Range;

#[cfg(feature = "storage")]
use embedded_storage::nor_flash::NorFlash;
use heapless::String;
#[cfg(feature = "storage")]
use heapless::Vec;

use crate::bytes::newer;
#[cfg(feature = "storage")]
use crate::bytes::{crc32, f32_at, u32_at, Put};
use crate::controller::{Fault, Figures};
#[cfg(feature = "storage")]
use crate::store::StoreError;

/// The newest entries the log keeps, at least.
pub const KEPT: usize = 32;
/// An entry's bytes.
pub const ENTRY_BYTES: usize = 64;
/// The words an entry of the layout before kept, bytes at most.
pub const WORDS_BYTES: usize = 32;
#[cfg(feature = "storage")]
const MAGIC: [u8; 2] = *b"DG";
/// The layout before: the words, cut.
#[cfg(feature = "storage")]
const MAGIC_WORDS: [u8; 2] = *b"DF";
#[cfg(feature = "storage")]
const WORDS_AT: usize = 28;
#[cfg(feature = "storage")]
const FIGURES_AT: usize = 28;
#[cfg(feature = "storage")]
const CRC_AT: usize = ENTRY_BYTES - 4;
const WATCHDOG: u8 = 0xF0;
const BROWN_OUT: u8 = 0xF1;

/// What an entry is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Cause {
    /// A fault the controller latched (`Fault::number`).
    Fault(u8),
    /// The watchdog reset the chip (logged at the boot after it).
    Watchdog,
    /// The supply fell below the brown-out level (logged at the boot after it).
    BrownOut,
}

impl Cause {
    /// The cause as the entry's byte.
    pub fn byte(self) -> u8 {
        match self {
            Cause::Fault(n) => n,
            Cause::Watchdog => WATCHDOG,
            Cause::BrownOut => BROWN_OUT,
        }
    }

    /// The cause of an entry's byte, if it is one.
    pub fn of(byte: u8) -> Option<Self> {
        match byte {
            WATCHDOG => Some(Cause::Watchdog),
            BROWN_OUT => Some(Cause::BrownOut),
            n => Fault::key_of(n).map(|_| Cause::Fault(n)),
        }
    }

    /// A reset's sentence (a fault's is its figures').
    pub fn words(self) -> &'static str {
        match self {
            Cause::Fault(n) => Fault::key_of(n).unwrap_or("fault"),
            Cause::Watchdog => "watchdog reset: a task hung or ran too long",
            Cause::BrownOut => "brown-out reset: the supply fell",
        }
    }

    /// Its key: the fault's (`FAULT_KEYS`), `watchdog` or `brown_out`.
    pub fn key(self) -> &'static str {
        match self {
            Cause::Fault(n) => Fault::key_of(n).unwrap_or("fault"),
            Cause::Watchdog => "watchdog",
            Cause::BrownOut => "brown_out",
        }
    }
}

/// One entry of the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Its number (set by `append`: one more than the newest).
    pub sequence: u32,
    pub cause: Cause,
    /// The board's tick since boot.
    pub tick: u32,
    /// Time since boot, s.
    pub seconds: f32,
    /// The voltage commanded when it came, V.
    pub volts: f32,
    pub current_amps: Option<f32>,
    pub stretch: Option<f32>,
    /// What happened: a fault's figures, or the cause alone.
    pub said: Said,
}

/// What an entry says happened, beside its cause.
#[derive(Clone, Debug, PartialEq)]
pub enum Said {
    /// The fault's figures: its sentence, whole.
    Figures(Figures),
    /// The cause says it all (a reset).
    Cause,
    /// An entry of the layout before: its words, cut at `WORDS_BYTES`.
    Words(String<WORDS_BYTES>),
}

/// An entry's sentence (`Entry::words`).
pub struct Words<'a>(&'a Entry);

impl fmt::Display for Words<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0.said {
            Said::Figures(fig) => match Fault::from_figures(fig) {
                Some(fault) => write!(f, "{fault}"),
                None => write!(
                    f,
                    "fault {} (figures this firmware does not read)",
                    fig.number
                ),
            },
            Said::Cause => f.write_str(self.0.cause.words()),
            Said::Words(words) => f.write_str(words),
        }
    }
}

impl Entry {
    /// An entry for `fault`: its figures.
    pub fn of_fault(fault: &Fault, tick: u32, seconds: f32, volts: f32) -> Self {
        Entry {
            sequence: 0,
            cause: Cause::Fault(fault.number()),
            tick,
            seconds,
            volts,
            current_amps: None,
            stretch: None,
            said: Said::Figures(fault.figures()),
        }
    }

    /// An entry for a reset the boot found (`Cause::Watchdog`, `Cause::BrownOut`), at tick 0.
    pub fn of_reset(cause: Cause) -> Self {
        Entry {
            sequence: 0,
            cause,
            tick: 0,
            seconds: 0.0,
            volts: 0.0,
            current_amps: None,
            stretch: None,
            said: Said::Cause,
        }
    }

    /// What happened, in words: the fault's sentence written again from its figures.
    pub fn words(&self) -> Words<'_> {
        Words(self)
    }

    #[cfg(feature = "storage")]
    fn to_bytes(&self) -> [u8; ENTRY_BYTES] {
        let mut out = [0u8; ENTRY_BYTES];
        let mut put = Put(&mut out, 0);
        let figures = match &self.said {
            Said::Figures(fig) => Some(fig),
            _ => None,
        };
        let (magic, third) = match &self.said {
            Said::Words(words) => (MAGIC_WORDS, words.len() as u8),
            Said::Figures(_) => (MAGIC, 0),
            Said::Cause => (MAGIC, 1),
        };
        put.bytes(&magic);
        put.bytes(&[self.cause.byte(), third]);
        put.bytes(&self.sequence.to_le_bytes());
        put.bytes(&self.tick.to_le_bytes());
        for x in [
            self.seconds,
            self.volts,
            self.current_amps.unwrap_or(f32::NAN),
            self.stretch.unwrap_or(f32::NAN),
        ] {
            put.bytes(&x.to_le_bytes());
        }
        match (&self.said, figures) {
            (Said::Words(words), _) => put.bytes(words.as_bytes()),
            (_, Some(fig)) => {
                put.bytes(&fig.details);
                for v in fig.values {
                    put.bytes(&v.to_le_bytes());
                }
            }
            _ => {}
        }
        let crc = crc32(out.get(..CRC_AT).unwrap_or(&[]));
        if let Some(tail) = out.get_mut(CRC_AT..) {
            tail.copy_from_slice(&crc.to_le_bytes());
        }
        out
    }

    #[cfg(feature = "storage")]
    /// An entry from its bytes, if they are a whole one (magic, CRC, fields).
    fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let body = bytes.get(..CRC_AT)?;
        if crc32(body) != u32_at(bytes, CRC_AT) {
            return None;
        }
        let cause = Cause::of(*bytes.get(2)?)?;
        let third = *bytes.get(3)?;
        let said = match (body.get(..2)?, third) {
            (m, len) if m == MAGIC_WORDS => {
                let len = usize::from(len);
                let text = core::str::from_utf8(bytes.get(WORDS_AT..WORDS_AT + len)?).ok()?;
                Said::Words(String::try_from(text).ok()?)
            }
            // A reset is said by its cause, whatever the byte.
            (m, _) if m == MAGIC && !matches!(cause, Cause::Fault(_)) => Said::Cause,
            (m, 1) if m == MAGIC => Said::Cause,
            (m, 0) if m == MAGIC => {
                let mut fig = Figures {
                    number: cause.byte(),
                    ..Figures::default()
                };
                fig.details
                    .copy_from_slice(bytes.get(FIGURES_AT..FIGURES_AT + 4)?);
                for (k, v) in fig.values.iter_mut().enumerate() {
                    *v = u32_at(bytes, FIGURES_AT + 4 + 4 * k);
                }
                Said::Figures(fig)
            }
            _ => return None,
        };
        let number = |x: f32| (!x.is_nan()).then_some(x);
        Some(Entry {
            sequence: u32_at(bytes, 4),
            cause,
            tick: u32_at(bytes, 8),
            seconds: f32_at(bytes, 12),
            volts: f32_at(bytes, 16),
            current_amps: number(f32_at(bytes, 20)),
            stretch: number(f32_at(bytes, 24)),
            said,
        })
    }
}

/// Put `item` in its place in `kept`, newest first by `sequence` (wrapping), the oldest
/// falling off the end: the newest `kept.len()` of a log read in any order, without a sort.
pub fn keep_newest<T>(kept: &mut [Option<T>], sequence: impl Fn(&T) -> u32, item: T) {
    let s = sequence(&item);
    let Some(at) = kept
        .iter()
        .position(|k| k.as_ref().is_none_or(|k| newer(s, sequence(k))))
    else {
        return;
    };
    let mut carry = Some(item);
    for slot in kept.iter_mut().skip(at) {
        carry = core::mem::replace(slot, carry);
        if carry.is_none() {
            break;
        }
    }
}

/// The two halves' starts and the slots a half holds, each room for `KEPT` entries.
#[cfg(feature = "storage")]
fn halves<F: NorFlash>(range: &Range<u32>) -> Result<([u32; 2], usize), StoreError> {
    let (starts, half) = crate::flash::halves::<F>(range).ok_or(StoreError::Range)?;
    let slots = half / ENTRY_BYTES.next_multiple_of(F::WRITE_SIZE.max(1));
    if slots < KEPT {
        return Err(StoreError::Range);
    }
    Ok((starts, slots))
}

/// A slot's offset: `k` whole slots into the half at `start`.
#[cfg(feature = "storage")]
fn slot_at<F: NorFlash>(start: u32, k: usize) -> u32 {
    start + (k * ENTRY_BYTES.next_multiple_of(F::WRITE_SIZE.max(1))) as u32
}

/// What a scan of the log found: the newest entry's sequence and half, and each half's first
/// erased slot (the slots after the last one written).
#[cfg(feature = "storage")]
struct Scan {
    newest: Option<(u32, usize)>,
    free: [Option<usize>; 2],
}

#[cfg(feature = "storage")]
fn scan<F: NorFlash>(
    flash: &mut F,
    range: &Range<u32>,
    mut each: impl FnMut(Entry),
) -> Result<Scan, StoreError> {
    let (starts, slots) = halves::<F>(range)?;
    let mut found = Scan {
        newest: None,
        free: [None; 2],
    };
    for (h, &start) in starts.iter().enumerate() {
        // Appends go in order: the slot after the last one written (whole or torn) is free.
        let mut free = Some(0);
        for k in 0..slots {
            let mut bytes = [0u8; ENTRY_BYTES];
            flash
                .read(slot_at::<F>(start, k), &mut bytes)
                .map_err(StoreError::flash)?;
            if bytes.iter().all(|&b| b == 0xFF) {
                continue;
            }
            free = (k + 1 < slots).then_some(k + 1);
            if let Some(entry) = Entry::from_bytes(&bytes) {
                if found.newest.is_none_or(|(s, _)| newer(entry.sequence, s)) {
                    found.newest = Some((entry.sequence, h));
                }
                each(entry);
            }
        }
        if let Some(slot) = found.free.get_mut(h) {
            *slot = free;
        }
    }
    Ok(found)
}

/// Append `entry` (its sequence set to one more than the newest): at the first erased slot
/// after the newest's half's last written one, or, that half full, at the start of the other
/// half: as it is if it is erased already (`prepare`), erased first if `may_erase` (else
/// `StoreError::LogFull`, nothing written: an erase stalls a chip that runs from the same
/// flash bank, for longer than its watchdog waits). The sequence number written.
#[cfg(feature = "storage")]
pub fn append<F: NorFlash>(
    mut flash: F,
    range: Range<u32>,
    entry: &Entry,
    may_erase: bool,
) -> Result<u32, StoreError> {
    let (starts, slots) = halves::<F>(&range)?;
    let found = scan(&mut flash, &range, |_| {})?;
    let (sequence, half) = match found.newest {
        Some((s, h)) => (s.wrapping_add(1), h),
        None => (1, 0),
    };
    let free = found.free.get(half).copied().flatten();
    let other = 1 - half;
    let (half, k) = match free {
        Some(k) => (half, k),
        // The other half erased already (`prepare`, or never written).
        None if found.free.get(other).copied().flatten() == Some(0) => (other, 0),
        None if !may_erase => return Err(StoreError::LogFull),
        None => {
            erase_half(&mut flash, &starts, other)?;
            (other, 0)
        }
    };
    if k >= slots {
        return Err(StoreError::Range);
    }
    let at = slot_at::<F>(starts.get(half).copied().ok_or(StoreError::Range)?, k);
    let bytes = Entry {
        sequence,
        ..entry.clone()
    }
    .to_bytes();
    // The body, then the CRC in a write of its own: a cut anywhere leaves a CRC that does not
    // match (the erased 0xFF…, or a part of it). Writes are whole words of the flash's.
    let word = F::WRITE_SIZE.max(1);
    let body_len = (CRC_AT / word) * word;
    let tail_len = (ENTRY_BYTES - body_len).next_multiple_of(word);
    let mut padded = [0xFFu8; ENTRY_BYTES + 32];
    for (slot, &byte) in padded.iter_mut().zip(bytes.get(..CRC_AT).unwrap_or(&[])) {
        *slot = byte;
    }
    let head = padded.get(..body_len).ok_or(StoreError::Range)?;
    flash.write(at, head).map_err(StoreError::flash)?;
    for (slot, &byte) in padded.iter_mut().zip(&bytes).skip(CRC_AT) {
        *slot = byte;
    }
    let tail = padded
        .get(body_len..body_len + tail_len)
        .ok_or(StoreError::Range)?;
    flash
        .write(at + body_len as u32, tail)
        .map_err(StoreError::flash)?;
    Ok(sequence)
}

/// Erase half `h` (its whole pages).
#[cfg(feature = "storage")]
fn erase_half<F: NorFlash>(flash: &mut F, starts: &[u32; 2], h: usize) -> Result<(), StoreError> {
    let start = starts.get(h).copied().ok_or(StoreError::Range)?;
    // The halves are the same length: the second's start less the first's.
    let [first, second] = *starts;
    flash
        .erase(start, start + (second - first))
        .map_err(StoreError::flash)
}

/// At boot, while a stall harms nothing (nothing driven, no watchdog yet): erase the other
/// half if the newest's holds `KEPT` entries or more (the newest `KEPT` are all there) and
/// the other is not erased, so that appends while running, which must not erase on a chip,
/// have the rest of this half and all of the other. With no entry at all and no free slot in
/// the first half (another program's bytes in the sectors, QEMU's zeroed RAM), the second is
/// erased, where the first append goes. Whether it erased.
#[cfg(feature = "storage")]
pub fn prepare<F: NorFlash>(mut flash: F, range: Range<u32>) -> Result<bool, StoreError> {
    let (starts, slots) = halves::<F>(&range)?;
    let found = scan(&mut flash, &range, |_| {})?;
    let Some((_, half)) = found.newest else {
        let free = |h: usize| found.free.get(h).copied().flatten();
        if free(0).is_some() || free(1) == Some(0) {
            return Ok(false);
        }
        erase_half(&mut flash, &starts, 1)?;
        return Ok(true);
    };
    let used = found.free.get(half).copied().flatten().unwrap_or(slots);
    let other = 1 - half;
    if used < KEPT || found.free.get(other).copied().flatten() == Some(0) {
        return Ok(false);
    }
    erase_half(&mut flash, &starts, other)?;
    Ok(true)
}

/// Every valid entry, in flash order (the board's `faults`: a list, or one entry, without
/// holding them all).
#[cfg(feature = "storage")]
pub fn each<F: NorFlash>(
    mut flash: F,
    range: Range<u32>,
    each: impl FnMut(Entry),
) -> Result<(), StoreError> {
    scan(&mut flash, &range, each).map(|_| ())
}

/// The valid entries, newest first (at most `KEPT`).
#[cfg(feature = "storage")]
pub fn read<F: NorFlash>(mut flash: F, range: Range<u32>) -> Result<Vec<Entry, KEPT>, StoreError> {
    let mut kept: [Option<Entry>; KEPT] = core::array::from_fn(|_| None);
    scan(&mut flash, &range, |entry| {
        keep_newest(&mut kept, |e| e.sequence, entry)
    })?;
    let mut list = Vec::new();
    for entry in kept.into_iter().flatten() {
        let _ = list.push(entry);
    }
    Ok(list)
}

/// Erase both halves: the log empty.
#[cfg(feature = "storage")]
pub fn clear<F: NorFlash>(mut flash: F, range: Range<u32>) -> Result<(), StoreError> {
    halves::<F>(&range)?;
    flash
        .erase(range.start, range.end)
        .map_err(StoreError::flash)
}
