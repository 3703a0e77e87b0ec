//! The settings' and the fault log's flash under QEMU, whose flash controller is not
//! emulated: `.uninit` RAM pages (cortex-m-rt does not zero them; QEMU's `sys_reset` keeps
//! them, as flash survives a power cycle), each erase then a stall as long as a chip's
//! sector erase (`watchdog::SECTOR_ERASE_MS` of QEMU's clock, interrupts masked, as the
//! chip's fetches stall), through the dog's `through_stall` as on the chip (not in the link
//! build, whose tick host-sim paces).

use de_resonator::board::FlashKeeper;
use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};
use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};

/// The settings' RAM pages (two slots of a page).
pub const SETTINGS_PAGES: usize = 2;
/// The fault log's RAM pages: two halves of two, 32 entries each.
pub const LOG_PAGES: usize = 4;

/// The RAM pages that a reset keeps: the settings' (`SETTINGS_PAGES`) and the fault log's
/// (`LOG_PAGES`). Given out once.
fn pages() -> Option<&'static mut [u8]> {
    use core::mem::MaybeUninit;
    use core::sync::atomic::{AtomicBool, Ordering};

    const BYTES: usize = (SETTINGS_PAGES + LOG_PAGES) * RAM_PAGE_BYTES;
    #[link_section = ".uninit.SETTINGS"]
    static mut RAM: MaybeUninit<[u8; BYTES]> = MaybeUninit::uninit();
    static TAKEN: AtomicBool = AtomicBool::new(false);
    if TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }
    // SAFETY: given out once (TAKEN), so this is the only reference. The bytes are whatever
    // the RAM holds (zeros at QEMU's power-up, the last run's after a reset): plain bytes,
    // which the store checks (magic, CRCs) before it believes any.
    Some(unsafe { (*core::ptr::addr_of_mut!(RAM)).assume_init_mut() })
}

/// The pages as the board keeps them: the settings' first, the fault log's after.
pub fn keeper() -> Option<FlashKeeper<SlowRam>> {
    let ram = pages()?;
    let settings = (SETTINGS_PAGES * RAM_PAGE_BYTES) as u32;
    let len = ram.len() as u32;
    Some(FlashKeeper {
        flash: SlowRam(RamFlash::new(ram)),
        range: 0..settings,
        log: Some(settings..len),
        // As the chip: the stand-in's erase stalls.
        erase_stalls: true,
    })
}

/// The RAM pages as flash, each erase stalling as a chip's sector erase.
pub struct SlowRam(RamFlash<'static>);

/// A chip's sector erase: `SECTOR_ERASE_MS` of QEMU's clock, interrupts masked, through the
/// watchdog's lengthened window.
#[cfg(not(feature = "link"))]
fn stall() {
    use super::{clock, dog::through_stall};
    use crate::watchdog::SECTOR_ERASE_MS;
    through_stall(|| {
        cortex_m::interrupt::free(|_| {
            let start = clock::micros();
            // Few reads of the clock: under -icount each ends QEMU's translated block.
            while clock::micros().wrapping_sub(start) < SECTOR_ERASE_MS * 1000 {
                cortex_m::asm::delay(100_000);
            }
        })
    });
}

/// The link build's tick is paced by host-sim, not by the chip's clock: no stall.
#[cfg(feature = "link")]
fn stall() {}

impl ErrorType for SlowRam {
    type Error = <RamFlash<'static> as ErrorType>::Error;
}

impl ReadNorFlash for SlowRam {
    const READ_SIZE: usize = <RamFlash<'static> as ReadNorFlash>::READ_SIZE;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }

    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl NorFlash for SlowRam {
    const WRITE_SIZE: usize = <RamFlash<'static> as NorFlash>::WRITE_SIZE;
    const ERASE_SIZE: usize = <RamFlash<'static> as NorFlash>::ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let done = self.0.erase(from, to);
        stall();
        done
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(offset, bytes)
    }
}

impl embedded_storage::nor_flash::MultiwriteNorFlash for SlowRam {}
