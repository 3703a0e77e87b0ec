//! Where `save` keeps the settings and the board its fault log: flash sectors 9 and 10 and
//! sectors 7 and 8 on the chip (memory.x's SETTINGS and FAULTLOG; the STM32F4 flash controller
//! through the HAL), `.uninit` RAM pages under QEMU (whose flash controller is not emulated;
//! `.uninit` survives `SCB::sys_reset`, as flash survives a power cycle). The layouts and the
//! power-cut safety are the core's `store` and `fault_log`.
//!
//! An erase stalls the chip for seconds (its code runs from the bank it erases), past the
//! watchdog: every erase runs through `watchdog::through_stall`, which lengthens the dog's
//! window around it. QEMU's stand-in stalls as long, interrupts masked, so its watchdog
//! stand-in bites there as the IWDG would without the lengthened window.

use de_resonator::board::FlashKeeper;

#[cfg(feature = "qemu")]
use crate::runtime::SETTINGS_PAGES;

/// The settings' flash as this build has it.
#[cfg(feature = "qemu")]
pub type SettingsFlash = SlowRam;
#[cfg(not(feature = "qemu"))]
pub type SettingsFlash = ChipFlash;

/// The flash (from the chip's flash controller, unused under QEMU) and the ranges of it the
/// settings and the fault log use, as the board keeps them.
pub fn open(controller: stm32f4xx_hal::pac::FLASH) -> Option<FlashKeeper<SettingsFlash>> {
    #[cfg(feature = "qemu")]
    {
        let _ = controller;
        let ram = crate::runtime::storage_ram()?;
        let settings = (SETTINGS_PAGES * de_resonator::flash::RAM_PAGE_BYTES) as u32;
        let len = ram.len() as u32;
        Some(FlashKeeper {
            flash: SlowRam(de_resonator::flash::RamFlash::new(ram)),
            range: 0..settings,
            log: Some(settings..len),
            // As the chip: the stand-in's erase stalls.
            erase_stalls: true,
        })
    }
    #[cfg(not(feature = "qemu"))]
    {
        extern "C" {
            /// memory.x: the settings' and the fault log's sectors as offsets from the start
            /// of flash.
            static _settings_offset: u8;
            static _settings_end: u8;
            static _faultlog_offset: u8;
            static _faultlog_end: u8;
        }
        let from = core::ptr::addr_of!(_settings_offset) as u32;
        let to = core::ptr::addr_of!(_settings_end) as u32;
        let log_from = core::ptr::addr_of!(_faultlog_offset) as u32;
        let log_to = core::ptr::addr_of!(_faultlog_end) as u32;
        Some(FlashKeeper {
            flash: ChipFlash(controller),
            range: from..to,
            log: Some(log_from..log_to),
            // A 128 KB sector's erase stalls the core 2-4 s (one bank).
            erase_stalls: true,
        })
    }
}

/// QEMU's flash: the RAM pages, each erase then a stall as long as a chip's sector erase
/// (`watchdog::SECTOR_ERASE_MS` of QEMU's clock, interrupts masked, as the chip's fetches
/// stall), through `watchdog::through_stall` as on the chip (not in the link build, whose
/// tick host-sim paces).
#[cfg(feature = "qemu")]
pub struct SlowRam(pub de_resonator::flash::RamFlash<'static>);

#[cfg(feature = "qemu")]
mod slow_ram {
    use de_resonator::flash::RamFlash;
    use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};

    use super::SlowRam;

    /// A chip's sector erase: `SECTOR_ERASE_MS` of QEMU's clock, interrupts masked, through
    /// the watchdog's lengthened window.
    #[cfg(not(feature = "link"))]
    fn stall() {
        use crate::chip::qemu_clock;
        use crate::watchdog::{through_stall, SECTOR_ERASE_MS};
        through_stall(|| {
            cortex_m::interrupt::free(|_| {
                let start = qemu_clock::micros();
                // Few reads of the clock: under -icount each ends QEMU's translated block.
                while qemu_clock::micros().wrapping_sub(start) < SECTOR_ERASE_MS * 1000 {
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
}

/// The STM32F4's flash controller as embedded-storage's `NorFlash` (each call blocks
/// until the controller is done; the HAL's waits on BSY), with what the HAL leaves out: stale
/// error flags cleared before each operation (one stale PGSERR would fail every later one),
/// the caches reset after an erase (RM0090 §3.5.2, as ST's HAL does), and each erase through
/// the watchdog's lengthened window. Not emulated by QEMU: compiled and clippy-checked in the
/// silicon builds only.
#[cfg(not(feature = "qemu"))]
pub struct ChipFlash(stm32f4xx_hal::pac::FLASH);

#[cfg(not(feature = "qemu"))]
mod chip {
    use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use stm32f4xx_hal::flash::{FlashExt, UnlockedFlash};
    use stm32f4xx_hal::pac::FLASH;

    use super::ChipFlash;

    /// Clear FLASH_SR's sticky flags (written 1 to clear): end of operation and every error.
    fn clear_flags(flash: &FLASH) {
        flash.sr().write(|w| {
            w.eop().clear_bit_by_one();
            w.operr().clear_bit_by_one();
            w.wrperr().clear_bit_by_one();
            w.pgaerr().clear_bit_by_one();
            w.pgperr().clear_bit_by_one();
            w.pgserr().clear_bit_by_one()
        });
    }

    /// Reset the instruction and data caches, each disabled around its reset (they may hold
    /// lines of the erased sector).
    fn flush_caches(flash: &FLASH) {
        let acr = flash.acr().read();
        if acr.icen().bit_is_set() {
            flash.acr().modify(|_, w| w.icen().clear_bit());
            flash.acr().modify(|_, w| w.icrst().set_bit());
            flash.acr().modify(|_, w| w.icrst().clear_bit());
            flash.acr().modify(|_, w| w.icen().set_bit());
        }
        if acr.dcen().bit_is_set() {
            flash.acr().modify(|_, w| w.dcen().clear_bit());
            flash.acr().modify(|_, w| w.dcrst().set_bit());
            flash.acr().modify(|_, w| w.dcrst().clear_bit());
            flash.acr().modify(|_, w| w.dcen().set_bit());
        }
    }

    impl ErrorType for ChipFlash {
        type Error = stm32f4xx_hal::flash::Error;
    }

    impl ReadNorFlash for ChipFlash {
        const READ_SIZE: usize = 1;

        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            let from = offset as usize;
            let memory = FlashExt::read(&self.0);
            let span = memory
                .get(from..from.saturating_add(bytes.len()))
                .ok_or(stm32f4xx_hal::flash::Error::Operation)?;
            bytes.copy_from_slice(span);
            Ok(())
        }

        fn capacity(&self) -> usize {
            FlashExt::len(&self.0)
        }
    }

    impl NorFlash for ChipFlash {
        const WRITE_SIZE: usize =
            <UnlockedFlash<'static> as embedded_storage::nor_flash::NorFlash>::WRITE_SIZE;
        const ERASE_SIZE: usize =
            <UnlockedFlash<'static> as embedded_storage::nor_flash::NorFlash>::ERASE_SIZE;

        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            clear_flags(&self.0);
            let done = crate::watchdog::through_stall(|| {
                embedded_storage::nor_flash::NorFlash::erase(&mut self.0.unlocked(), from, to)
            });
            flush_caches(&self.0);
            done
        }

        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            clear_flags(&self.0);
            embedded_storage::nor_flash::NorFlash::write(&mut self.0.unlocked(), offset, bytes)
        }
    }

    impl embedded_storage::nor_flash::MultiwriteNorFlash for ChipFlash {}
}
