//! The fault log in flash (`fault_log`), on the RAM flash that can tear a write at any byte:
//! entries read back as written, newest first, the `KEPT` newest across the halves' turns; a
//! power cut at any byte of any append (its erase of the other half included) loses nothing
//! but the entry in flight; garbage holds no entry; `clear` empties the log.
#![cfg(feature = "storage")]

use de_resonator::fault_log::{self, Cause, Entry, KEPT};
use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};
use de_resonator::store::StoreError;
use de_resonator::{FailureMode, Fault};

/// Two halves of two pages, as the firmware's QEMU stand-in has: 32 entries a half.
const PAGES: usize = 4;
const RANGE: core::ops::Range<u32> = 0..(PAGES * RAM_PAGE_BYTES) as u32;
const PER_HALF: usize = PAGES / 2 * RAM_PAGE_BYTES / 64;

fn erased() -> Vec<u8> {
    vec![0xFF; PAGES * RAM_PAGE_BYTES]
}

/// The n-th entry of a sequence: each differs from the others in every field.
fn nth(n: u32) -> Entry {
    let fault = Fault::Limit {
        mode: FailureMode::Emi,
        tick: 1000 + n,
    };
    Entry {
        current_amps: Some(1e-6 * n as f32),
        stretch: (!n.is_multiple_of(3)).then_some(2.0 + n as f32 / 1000.0),
        ..Entry::of_fault(&fault, 1000 + n, 1.0 + n as f32 / 1000.0, 7000.0 + n as f32)
    }
}

fn append(bytes: &mut [u8], entry: &Entry, fail_after: Option<usize>) -> Result<u32, StoreError> {
    let mut flash = RamFlash::new(bytes);
    flash.fail_after = fail_after;
    fault_log::append(&mut flash, RANGE, entry, true)
}

fn read(bytes: &mut [u8]) -> Vec<Entry> {
    fault_log::read(RamFlash::new(bytes), RANGE)
        .unwrap()
        .to_vec()
}

/// `expected` as the log gives it: the n-th entry with its sequence n + 1, newest first.
fn newest_first(ns: impl DoubleEndedIterator<Item = u32>) -> Vec<Entry> {
    ns.rev()
        .map(|n| Entry {
            sequence: n + 1,
            ..nth(n)
        })
        .collect()
}

#[test]
fn entries_read_back_newest_first_with_their_data() {
    let mut bytes = erased();
    for n in 0..5 {
        assert_eq!(append(&mut bytes, &nth(n), None), Ok(n + 1));
    }
    let log = read(&mut bytes);
    assert_eq!(log, newest_first(0..5));
    let newest = &log[0];
    assert_eq!(newest.cause, Cause::Fault(19));
    assert_eq!(newest.cause.key(), "limit");
    let sentence = Fault::Limit {
        mode: FailureMode::Emi,
        tick: 1004,
    }
    .to_string();
    assert!(sentence.len() > 32, "longer than the layout before kept");
    assert_eq!(
        newest.words().to_string(),
        sentence,
        "the fault's own sentence, whole, written again from its figures"
    );
}

#[test]
fn the_newest_kept_across_the_halves_turns() {
    let mut bytes = erased();
    const { assert!(PER_HALF >= KEPT) };
    for n in 0..(5 * PER_HALF as u32 + 7) {
        append(&mut bytes, &nth(n), None).unwrap();
        let log = read(&mut bytes);
        let from = (n + 1).saturating_sub(KEPT as u32);
        assert_eq!(log, newest_first(from..n + 1), "after {} appends", n + 1);
    }
}

/// Bytes an append changes (written or erased), counted by a budget that never runs out.
fn bytes_of_append(bytes: &[u8], entry: &Entry) -> usize {
    let mut copy = bytes.to_vec();
    let budget = usize::MAX / 2;
    let mut flash = RamFlash::new(&mut copy);
    flash.fail_after = Some(budget);
    fault_log::append(&mut flash, RANGE, entry, true).unwrap();
    budget - flash.fail_after.unwrap()
}

#[test]
fn a_power_cut_at_any_byte_of_any_append_loses_only_the_entry_in_flight() {
    let mut bytes = erased();
    let mut cuts = 0;
    // Through two turns of the halves: appends into erased slots and appends that erase.
    for n in 0..(2 * PER_HALF as u32 + 3) {
        let before = read(&mut bytes);
        let changed = bytes_of_append(&bytes, &nth(n));
        for cut in (0..changed).step_by(if changed > 200 { 7 } else { 1 }) {
            let mut torn = bytes.clone();
            assert!(append(&mut torn, &nth(n), Some(cut)).is_err());
            let after = read(&mut torn);
            // Everything before, but what an erase of the older half takes (entries beyond
            // the KEPT newest), and the new entry whole or not at all.
            let kept: Vec<&Entry> = before.iter().take(KEPT).collect();
            for old in &kept {
                assert!(
                    after.contains(old),
                    "append {n} cut at byte {cut}: entry {} lost",
                    old.sequence
                );
            }
            assert!(
                after.iter().all(|e| before.contains(e)
                    || *e
                        == Entry {
                            sequence: n + 1,
                            ..nth(n)
                        }),
                "append {n} cut at byte {cut}: an entry that was never written"
            );
            // The log goes on after the cut.
            let next = append(&mut torn, &nth(n), None).unwrap();
            assert_eq!(read(&mut torn)[0].sequence, next);
            cuts += 1;
        }
        append(&mut bytes, &nth(n), None).unwrap();
    }
    // 67 appends of 64 bytes cut at each byte, two of them with a 2 KB erase cut at every
    // 7th.
    assert!(cuts > 4000, "{cuts} cuts");
}

#[test]
fn garbage_holds_no_entry_and_an_append_works_on_it() {
    let mut bytes: Vec<u8> = (0..PAGES * RAM_PAGE_BYTES)
        .map(|i| (i * 7919 % 251) as u8)
        .collect();
    assert_eq!(read(&mut bytes), vec![]);
    // Garbage in every slot: no slot is free; the append erases the other half.
    append(&mut bytes, &nth(0), None).unwrap();
    assert_eq!(read(&mut bytes), newest_first(0..1));
}

/// A log over bytes that were never this log's (another program's in the sectors, QEMU's
/// zeroed RAM) takes entries while running, when it must not erase: the boot's `prepare`
/// erased where the first goes.
#[test]
fn the_boots_prepare_readies_a_log_over_foreign_bytes() {
    for fill in [0x00u8, 0x5A] {
        let mut bytes = vec![fill; PAGES * RAM_PAGE_BYTES];
        let no_erase = |bytes: &mut Vec<u8>, n: u32| {
            fault_log::append(RamFlash::new(bytes), RANGE, &nth(n), false)
        };
        assert_eq!(
            no_erase(&mut bytes, 0),
            Err(StoreError::LogFull),
            "{fill:#x}"
        );
        let prepare = |bytes: &mut Vec<u8>| fault_log::prepare(RamFlash::new(bytes), RANGE);
        assert_eq!(prepare(&mut bytes), Ok(true), "{fill:#x}");
        assert_eq!(prepare(&mut bytes), Ok(false), "{fill:#x}: once");
        for n in 0..3 {
            assert_eq!(no_erase(&mut bytes, n), Ok(n + 1), "{fill:#x}");
        }
        assert_eq!(read(&mut bytes), newest_first(0..3), "{fill:#x}");
    }
}

#[test]
fn clear_empties_the_log() {
    let mut bytes = erased();
    for n in 0..3 {
        append(&mut bytes, &nth(n), None).unwrap();
    }
    fault_log::clear(RamFlash::new(&mut bytes), RANGE).unwrap();
    assert_eq!(read(&mut bytes), vec![]);
    assert_eq!(append(&mut bytes, &nth(9), None), Ok(1));
}

#[test]
fn a_range_without_room_for_the_kept_entries_is_refused() {
    let mut bytes = erased();
    let small = 0..(2 * RAM_PAGE_BYTES) as u32;
    let got = fault_log::append(RamFlash::new(&mut bytes), small, &nth(0), true);
    assert_eq!(
        got,
        Err(StoreError::Range),
        "two 1 KB halves hold 10 entries each"
    );
}

/// Appends that must not erase (a chip, running): into the other half while it is erased;
/// both full, nothing written and said; `prepare` at boot erases the older half (the newest
/// holding `KEPT`), and appends go on without an erase.
#[test]
fn appends_that_must_not_erase_and_the_boots_prepare() {
    let mut bytes = erased();
    let append = |bytes: &mut Vec<u8>, n: u32| {
        fault_log::append(RamFlash::new(bytes), RANGE, &nth(n), false)
    };
    for n in 0..2 * PER_HALF as u32 {
        assert_eq!(append(&mut bytes, n), Ok(n + 1), "both halves fill");
    }
    let before = bytes.clone();
    assert_eq!(append(&mut bytes, 99), Err(StoreError::LogFull));
    assert!(bytes == before, "nothing written");
    let prepare = |bytes: &mut Vec<u8>| fault_log::prepare(RamFlash::new(bytes), RANGE);
    assert_eq!(prepare(&mut bytes), Ok(true));
    assert_eq!(prepare(&mut bytes), Ok(false), "once");
    let top = 2 * PER_HALF as u32;
    assert_eq!(read(&mut bytes), newest_first(top - KEPT as u32..top));
    assert_eq!(append(&mut bytes, top), Ok(top + 1));
    // Fewer than KEPT in the newest half: the older half is kept.
    let mut bytes = erased();
    for n in 0..PER_HALF as u32 + 3 {
        append(&mut bytes, n).unwrap();
    }
    assert_eq!(prepare(&mut bytes), Ok(false));
    assert_eq!(read(&mut bytes).len(), KEPT);
}

#[test]
fn resets_are_entries_too() {
    let mut bytes = erased();
    append(&mut bytes, &Entry::of_reset(Cause::Watchdog), None).unwrap();
    append(&mut bytes, &Entry::of_reset(Cause::BrownOut), None).unwrap();
    let log = read(&mut bytes);
    assert_eq!(
        log.iter().map(|e| e.cause.key()).collect::<Vec<_>>(),
        ["brown_out", "watchdog"]
    );
    assert_eq!(
        log[1].words().to_string(),
        "watchdog reset: a task hung or ran too long"
    );
}

/// An entry of the layout before (magic `DF`, its words cut at 32 bytes) still reads, as it
/// was written: a firmware update keeps the log it finds.
#[test]
fn an_entry_of_the_layout_before_reads_as_it_was() {
    let mut bytes = erased();
    let words = "sensor sample 39 is not a number";
    let mut old = [0u8; 64];
    old[..2].copy_from_slice(b"DF");
    old[2] = 12; // Fault::Sensor's number
    old[3] = words.len() as u8;
    old[4..8].copy_from_slice(&7u32.to_le_bytes());
    old[8..12].copy_from_slice(&3900u32.to_le_bytes());
    old[12..16].copy_from_slice(&3.9f32.to_le_bytes());
    old[16..20].copy_from_slice(&5.0f32.to_le_bytes());
    old[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    old[24..28].copy_from_slice(&f32::NAN.to_le_bytes());
    old[28..28 + words.len()].copy_from_slice(words.as_bytes());
    // CRC-32 (IEEE 802.3), written out here: the layout's, not the code's helper.
    let mut crc = !0u32;
    for &b in &old[..60] {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    old[60..].copy_from_slice(&(!crc).to_le_bytes());
    bytes[..64].copy_from_slice(&old);
    let log = read(&mut bytes);
    assert_eq!(log.len(), 1);
    assert_eq!(
        (log[0].sequence, log[0].cause.key(), log[0].tick),
        (7, "sensor", 3900)
    );
    assert_eq!(log[0].words().to_string(), words);
    // The next entry is written in the new layout after it, and both read.
    assert_eq!(append(&mut bytes, &nth(0), None), Ok(8));
    assert_eq!(read(&mut bytes).len(), 2);
}
