//! Where `save` keeps the settings and the board its fault log: flash sectors 9 and 10 and
//! sectors 7 and 8 on the chip (memory.x's SETTINGS and FAULTLOG; the STM32F4 flash controller
//! through the HAL), `qemu::flash`'s RAM pages under QEMU (whose flash controller is not
//! emulated). The layouts and the power-cut safety are the core's `store` and `fault_log`.
//!
//! An erase stalls the chip for seconds (its code runs from the bank it erases), past the
//! watchdog: every erase runs through `watchdog::through_stall`, which lengthens the dog's
//! window around it. QEMU's stand-in stalls as long, interrupts masked, so its watchdog
//! stand-in bites there as the IWDG would without the lengthened window.

use de_resonator::board::FlashKeeper;

/// The settings' flash as this build has it.
#[cfg(feature = "qemu")]
pub type SettingsFlash = crate::qemu::flash::SlowRam;
#[cfg(not(feature = "qemu"))]
pub type SettingsFlash = ChipFlash;

/// The flash (from the chip's flash controller, unused under QEMU) and the ranges of it the
/// settings and the fault log use, as the board keeps them.
pub fn open(controller: stm32f4xx_hal::pac::FLASH) -> Option<FlashKeeper<SettingsFlash>> {
    #[cfg(feature = "qemu")]
    {
        let _ = controller;
        crate::qemu::flash::keeper()
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
