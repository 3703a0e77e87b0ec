//! Settings saved in flash (`store`), on the RAM flash that can tear a write at any byte: a
//! power cut anywhere in any save (either slot, every byte of its erase and its writes) never
//! loses the last good settings, a corrupted record is skipped, and a blob of another version
//! is refused by name.
#![cfg(feature = "storage")]

use de_resonator::controller::Held;
use de_resonator::flash::{self, RamFlash, RamFlashWords, RAM_PAGE_BYTES};
use de_resonator::store::{self, StoreError, BLOB_BYTES};
use de_resonator::{Setting, Settings};
use embedded_storage::nor_flash::ReadNorFlash;

/// Two pages, as the firmware's QEMU stand-in has.
const PAGES: usize = 2;
const RANGE: core::ops::Range<u32> = 0..(PAGES * RAM_PAGE_BYTES) as u32;

fn erased() -> Vec<u8> {
    vec![0xFF; PAGES * RAM_PAGE_BYTES]
}

/// The n-th settings of a sequence: each differs from the others.
fn nth(n: usize) -> Settings {
    Settings {
        slew_volts_per_second: 1000.0 + n as f32,
        ac_volts: n as f32,
        stuck_samples: if n.is_multiple_of(2) {
            None
        } else {
            Some(n as u32)
        },
        ..Settings::for_target(40.0 + n as f32 / 8.0)
    }
}

fn save(
    bytes: &mut [u8],
    settings: &Settings,
    fail_after: Option<usize>,
) -> Result<(), StoreError> {
    let mut flash = RamFlash::new(bytes);
    flash.fail_after = fail_after;
    store::save(&mut flash, RANGE, settings)
}

/// The settings saved, onto the defaults (every test's blob holds every setting).
fn load(bytes: &mut [u8]) -> Result<Option<Settings>, StoreError> {
    store::load(RamFlash::new(bytes), RANGE)
        .map(|held| held.map(|h| h.onto(Settings::for_target(0.0)).0))
}

/// Bytes a save changes (written or erased), counted by a budget that never runs out.
fn bytes_of_save(bytes: &[u8], settings: &Settings) -> usize {
    let mut copy = bytes.to_vec();
    let budget = usize::MAX / 2;
    let mut flash = RamFlash::new(&mut copy);
    flash.fail_after = Some(budget);
    store::save(&mut flash, RANGE, settings).unwrap();
    budget - flash.fail_after.unwrap()
}

#[test]
fn settings_read_back_as_saved() {
    let mut bytes = erased();
    assert_eq!(load(&mut bytes), Ok(None));
    for n in 0..50 {
        save(&mut bytes, &nth(n), None).unwrap();
        assert_eq!(load(&mut bytes), Ok(Some(nth(n))), "save {n}");
    }
}

/// Every save of a run that wraps the pages several times (so the cut also lands in a page's
/// erase), cut at every byte it changes: the settings read afterwards are the last good ones
/// (or the new ones, once the item is whole), and the next save works.
#[test]
fn a_power_cut_at_any_byte_of_any_save_loses_nothing() {
    let mut bytes = erased();
    let mut cuts = 0;
    for n in 0..40 {
        let before = nth(n);
        let after = nth(n + 1);
        if n > 0 {
            assert_eq!(load(&mut bytes), Ok(Some(before)));
        }
        let total = bytes_of_save(&bytes, &after);
        for cut in 0..total {
            let mut torn = bytes.clone();
            assert!(
                save(&mut torn, &after, Some(cut)).is_err(),
                "save {n} cut at {cut}"
            );
            let read = load(&mut torn);
            let expected = if n == 0 { None } else { Some(before) };
            assert!(
                read == Ok(expected) || read == Ok(Some(after)),
                "save {n} cut at byte {cut} of {total}: read {read:?}"
            );
            // The storage goes on: the next save is read back.
            save(&mut torn, &nth(100 + n), None).unwrap();
            assert_eq!(load(&mut torn), Ok(Some(nth(100 + n))));
            cuts += 1;
        }
        save(&mut bytes, &after, None).unwrap();
    }
    println!("{cuts} power cuts, none lost the last good settings");
    assert!(cuts > 40 * BLOB_BYTES);
}

/// A flipped bit in the newest record: it is skipped (its CRC), the one before is read.
#[test]
fn a_corrupted_item_is_skipped() {
    let mut bytes = erased();
    save(&mut bytes, &nth(1), None).unwrap();
    save(&mut bytes, &nth(2), None).unwrap();
    // The newest record's blob, found in the flash.
    let blob = store::encode(&nth(2));
    let at = bytes
        .windows(blob.len())
        .position(|w| w == blob)
        .expect("the blob is stored as is");
    bytes[at + 10] ^= 0x01;
    assert_eq!(load(&mut bytes), Ok(Some(nth(1))));
}

/// A blob of a layout version this code does not read: refused with its version, never read
/// as settings.
#[test]
fn a_blob_of_another_version_is_refused() {
    let mut bytes = erased();
    let mut old = store::encode(&nth(3));
    old[0..2].copy_from_slice(&7u16.to_le_bytes());
    store::save_blob(RamFlash::new(&mut bytes), RANGE, &old).unwrap();
    let refused = load(&mut bytes);
    assert_eq!(
        refused,
        Err(StoreError::Version {
            version: 7,
            count: Setting::ALL.len() as u16
        })
    );
    let message = refused.unwrap_err().to_string();
    assert!(
        message.contains("version 7") && message.contains("ignored"),
        "{message}"
    );
    let again = store::decode(&store::encode(&nth(4))).unwrap();
    assert_eq!(again.onto(Settings::for_target(0.0)).0, nth(4));
}

/// Settings by id: a blob written before a setting was added (here, one lacking
/// `trim_pulse_volts`, as a firmware without it wrote them) keeps every value it holds and
/// takes the base's for the one it lacks, saying which; a blob holding a setting this
/// firmware does not know (a newer one's) is refused by name; entries in any order read the
/// same.
#[test]
fn an_older_blob_keeps_its_values_and_a_newer_one_is_refused() {
    let saved = nth(9);
    let blob = store::encode(&saved);
    let entries: Vec<[u8; 8]> = blob[4..].chunks(8).map(|c| c.try_into().unwrap()).collect();
    let lacking = Setting::from_key("trim_pulse_volts").unwrap();
    let older: Vec<u8> = 2u16
        .to_le_bytes()
        .into_iter()
        .chain((Setting::ALL.len() as u16 - 1).to_le_bytes())
        .chain(
            entries
                .iter()
                .rev()
                .filter(|e| u16::from_le_bytes([e[0], e[1]]) != u16::from(lacking.id()))
                .flatten()
                .copied(),
        )
        .collect();
    let base = Settings {
        trim_pulse_volts: 123.0,
        ..Settings::for_target(30.0)
    };
    let (settings, new) = store::decode(&older).unwrap().onto(base);
    assert_eq!(
        settings,
        Settings {
            trim_pulse_volts: 123.0,
            ..saved
        }
    );
    assert_eq!(new.iter().collect::<Vec<_>>(), [lacking]);
    // One more entry, of an id no setting has: refused by name.
    let mut newer = blob.to_vec();
    newer[2..4].copy_from_slice(&(Setting::ALL.len() as u16 + 1).to_le_bytes());
    newer.extend([200, 0, 0, 0, 0, 0, 128, 63]);
    assert_eq!(
        store::decode(&newer),
        Err(StoreError::UnknownSetting { id: 200 })
    );
}

/// A range of garbage (a stranger's bytes, RAM at power-up) holds no settings; a save
/// works on it; `erase` forgets what was saved.
#[test]
fn garbage_holds_no_settings_and_a_save_works_on_it() {
    for fill in [0x00u8, 0x5A] {
        let mut bytes = vec![fill; PAGES * RAM_PAGE_BYTES];
        assert_eq!(load(&mut bytes), Ok(None));
        save(&mut bytes, &nth(5), None).unwrap();
        assert_eq!(load(&mut bytes), Ok(Some(nth(5))));
        store::erase(RamFlash::new(&mut bytes), RANGE).unwrap();
        assert_eq!(load(&mut bytes), Ok(None));
    }
}

/// A range that is not two slots of whole pages is refused.
#[test]
fn a_range_that_is_not_two_slots_is_refused() {
    let mut bytes = erased();
    for range in [
        0..RAM_PAGE_BYTES as u32,
        0..3 * RAM_PAGE_BYTES as u32 / 2,
        100..2148,
    ] {
        let mut flash = RamFlash::new(&mut bytes);
        assert_eq!(
            store::save(&mut flash, range.clone(), &nth(1)),
            Err(StoreError::Range),
            "{range:?}"
        );
    }
}

/// The blob's documented layout: version 2, count, then each of the 23 settings as its id
/// (u16), two zero bytes and its value (f32): 188 bytes; a blob whose count does not match
/// its length is refused.
#[test]
fn the_blob_is_the_documented_one() {
    assert_eq!(BLOB_BYTES, 2 + 2 + 8 * de_resonator::Setting::ALL.len());
    assert_eq!(BLOB_BYTES, 188);
    let blob = store::encode(&nth(7));
    assert_eq!(u16::from_le_bytes([blob[0], blob[1]]), 2);
    assert_eq!(u16::from_le_bytes([blob[2], blob[3]]), 23);
    for (k, entry) in blob[4..].chunks(8).enumerate() {
        assert_eq!(u16::from_le_bytes([entry[0], entry[1]]), k as u16);
        assert_eq!(&entry[2..4], [0, 0]);
    }
    let mut short = blob;
    short[2] = 15;
    assert_eq!(
        store::decode(&short),
        Err(StoreError::Version {
            version: store::BLOB_VERSION,
            count: 15
        })
    );
    assert!(store::decode(&blob[..60]).is_err());
}

/// A range anywhere in the flash: saves touch its bytes only; past the flash's end, the
/// flash's own error.
#[test]
fn saves_stay_inside_their_range() {
    let page = RAM_PAGE_BYTES as u32;
    // Outside the range: bytes an erase would change (to 0xFF).
    let mut bytes = vec![0x00; 6 * RAM_PAGE_BYTES];
    bytes[RAM_PAGE_BYTES..5 * RAM_PAGE_BYTES].fill(0xFF);
    let range = page..5 * page;
    for n in 0..6 {
        let mut flash = RamFlash::new(&mut bytes);
        store::save(&mut flash, range.clone(), &nth(n)).unwrap();
        assert_eq!(
            store::load(&mut flash, range.clone()),
            Ok(Some(Held::all(&nth(n))))
        );
        let outside = bytes[..RAM_PAGE_BYTES]
            .iter()
            .chain(&bytes[5 * RAM_PAGE_BYTES..]);
        assert!(
            outside.copied().all(|b| b == 0x00),
            "save {n} wrote outside"
        );
    }
    let mut flash = RamFlash::new(&mut bytes);
    assert_eq!(
        store::save(&mut flash, 4 * page..8 * page, &nth(1)),
        Err(StoreError::Flash(flash::FlashKind::OutOfBounds))
    );
    use embedded_storage::nor_flash::NorFlashErrorKind as Kind;
    assert_eq!(
        flash::FlashKind::from(Kind::NotAligned),
        flash::FlashKind::NotAligned
    );
    assert_eq!(
        flash::FlashKind::from(Kind::OutOfBounds),
        flash::FlashKind::OutOfBounds
    );
}

/// Flashes of other word sizes (1 to 32 bytes, as NOR flashes have): every save is whole
/// words (the RAM flash refuses a misaligned write, as real flash does), a power cut at any
/// byte still loses nothing.
#[test]
fn every_word_size_is_written_whole_and_survives_a_cut() {
    fn run<const WORD: usize>() {
        let mut bytes = erased();
        for n in 0..4 {
            let mut flash = RamFlashWords::<WORD>::new(&mut bytes);
            store::save(&mut flash, RANGE, &nth(n)).unwrap();
            assert_eq!(
                store::load(&mut flash, RANGE),
                Ok(Some(Held::all(&nth(n)))),
                "{WORD}"
            );
        }
        for cut in 0..RAM_PAGE_BYTES + 200 {
            let mut torn = bytes.clone();
            let mut flash = RamFlashWords::<WORD>::new(&mut torn);
            flash.fail_after = Some(cut);
            let _ = store::save(&mut flash, RANGE, &nth(9));
            flash.fail_after = None;
            let read = store::load(&mut flash, RANGE);
            assert!(
                read == Ok(Some(Held::all(&nth(3)))) || read == Ok(Some(Held::all(&nth(9)))),
                "{WORD} cut {cut}"
            );
        }
        assert_eq!(
            RamFlashWords::<WORD>::new(&mut bytes).capacity(),
            PAGES * RAM_PAGE_BYTES
        );
    }
    run::<1>();
    run::<2>();
    run::<8>();
    run::<16>();
    run::<32>();
    // Words longer than the store's record buffer allows: refused, nothing half-written.
    let mut bytes = erased();
    let mut flash = RamFlashWords::<256>::new(&mut bytes);
    assert_eq!(
        store::save(&mut flash, RANGE, &nth(1)),
        Err(StoreError::Range)
    );
}

/// The RAM flash refuses what real NOR flash refuses: a write of part of a word, an erase of
/// part of a page.
#[test]
fn the_ram_flash_refuses_misaligned_writes_and_erases() {
    use embedded_storage::nor_flash::{NorFlash, NorFlashError, NorFlashErrorKind};
    let mut bytes = erased();
    let mut flash = RamFlash::new(&mut bytes);
    let kind = |r: Result<(), flash::RamFlashError>| r.map_err(|e| e.kind());
    let not_aligned = Err(NorFlashErrorKind::NotAligned);
    assert_eq!(kind(flash.write(1, &[0; 4])), not_aligned);
    assert_eq!(kind(flash.write(4, &[0; 3])), not_aligned);
    assert_eq!(kind(flash.write(4, &[0; 4])), Ok(()));
    assert_eq!(kind(flash.erase(512, 1024)), not_aligned);
    assert_eq!(kind(flash.erase(0, 512)), not_aligned);
    assert_eq!(kind(flash.erase(0, 1024)), Ok(()));
}

/// A record as a firmware writes it in the first slot: magic, sequence number, blob, CRC-32
/// of all before it (docs/firmware.md), over erased flash.
fn record_in_first_slot(blob: &[u8]) -> Vec<u8> {
    let mut record: Vec<u8> = b"DERS"
        .iter()
        .copied()
        .chain(1u32.to_le_bytes())
        .chain(blob.iter().copied())
        .collect();
    let crc = de_resonator::bytes::crc32(&record);
    record.extend(crc.to_le_bytes());
    let mut bytes = erased();
    bytes[..record.len()].copy_from_slice(&record);
    bytes
}

/// A newer firmware's blob of as many settings as a set has room for (32: a `SettingSet` is
/// a 32-bit word) reads back from flash whole and is refused by its first unknown id, saying
/// so; a record longer than that is passed over as no record (the image's settings boot), as
/// a torn one is.
#[test]
fn a_blob_of_thirty_two_settings_is_read_whole_and_one_of_thirty_three_is_not() {
    let mut newer = store::encode(&nth(5)).to_vec();
    let known = Setting::ALL.len();
    for id in known..32 {
        newer.extend([id as u8, 0, 0, 0, 0, 0, 128, 63]);
    }
    newer[2..4].copy_from_slice(&32u16.to_le_bytes());
    let mut bytes = record_in_first_slot(&newer);
    assert_eq!(
        load(&mut bytes),
        Err(StoreError::UnknownSetting { id: known as u16 })
    );
    // Today's, written the same way: read whole.
    let mut bytes = record_in_first_slot(&store::encode(&nth(6)));
    assert_eq!(load(&mut bytes), Ok(Some(nth(6))));
    newer.extend([32, 0, 0, 0, 0, 0, 128, 63]);
    newer[2..4].copy_from_slice(&33u16.to_le_bytes());
    let mut bytes = record_in_first_slot(&newer);
    assert_eq!(load(&mut bytes), Ok(None));
    // The same 33 as a blob handed to `decode`: refused, its version and count said.
    assert_eq!(
        store::decode(&newer),
        Err(StoreError::Version {
            version: 2,
            count: 33
        })
    );
}
