//! Where `save` keeps the settings and the board its fault log: flash sectors 9 and 10 and
//! sectors 7 and 8 on the chip (memory.x's SETTINGS and FAULTLOG; the STM32F4 flash controller
//! through the HAL), `.uninit` RAM pages under QEMU (whose flash controller is not emulated;
//! `.uninit` survives `SCB::sys_reset`, as flash survives a power cycle). The layouts and the
//! power-cut safety are the core's `store` and `fault_log`.

use de_resonator::store::FlashKeeper;

/// The settings' RAM pages under QEMU (two slots of a page).
pub const SETTINGS_PAGES: usize = 2;
/// The fault log's RAM pages under QEMU: two halves of two, 32 entries each.
pub const LOG_PAGES: usize = 4;

/// The settings' flash as this build has it.
#[cfg(feature = "qemu")]
pub type SettingsFlash = de_resonator::store::RamFlash<'static>;
#[cfg(not(feature = "qemu"))]
pub type SettingsFlash = ChipFlash;

/// The flash (from the chip's flash controller, unused under QEMU) and the ranges of it the
/// settings and the fault log use, as the board keeps them.
pub fn open(controller: stm32f4xx_hal::pac::FLASH) -> Option<FlashKeeper<SettingsFlash>> {
    #[cfg(feature = "qemu")]
    {
        let _ = controller;
        let ram = crate::runtime::storage_ram()?;
        let settings = (SETTINGS_PAGES * de_resonator::store::RAM_PAGE_BYTES) as u32;
        let len = ram.len() as u32;
        Some(FlashKeeper {
            flash: de_resonator::store::RamFlash::new(ram),
            range: 0..settings,
            log: Some(settings..len),
            // RAM: an erase is over at once.
            erase_stalls: false,
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
        let flash = stm32f4xx_hal::flash::LockedFlash::new(controller);
        Some(FlashKeeper {
            flash: ChipFlash(flash),
            range: from..to,
            log: Some(log_from..log_to),
            // A 128 KB sector's erase stalls the core 2-4 s (one bank), past the watchdog.
            erase_stalls: true,
        })
    }
}

/// The STM32F4's flash controller as embedded-storage's async `NorFlash` (each call blocks
/// until the controller is done; the HAL's waits on BSY). Not emulated by QEMU: compiled and
/// clippy-checked in the silicon builds only.
#[cfg(not(feature = "qemu"))]
pub struct ChipFlash(stm32f4xx_hal::flash::LockedFlash);

#[cfg(not(feature = "qemu"))]
mod chip {
    use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use stm32f4xx_hal::flash::{FlashExt, UnlockedFlash};

    use super::ChipFlash;

    impl ErrorType for ChipFlash {
        type Error = stm32f4xx_hal::flash::Error;
    }

    impl ReadNorFlash for ChipFlash {
        const READ_SIZE: usize = 1;

        async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            embedded_storage::nor_flash::ReadNorFlash::read(&mut self.0, offset, bytes)
        }

        fn capacity(&self) -> usize {
            embedded_storage::nor_flash::ReadNorFlash::capacity(&self.0)
        }
    }

    impl NorFlash for ChipFlash {
        const WRITE_SIZE: usize =
            <UnlockedFlash<'static> as embedded_storage::nor_flash::NorFlash>::WRITE_SIZE;
        const ERASE_SIZE: usize =
            <UnlockedFlash<'static> as embedded_storage::nor_flash::NorFlash>::ERASE_SIZE;

        async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            embedded_storage::nor_flash::NorFlash::erase(&mut self.0.unlocked(), from, to)
        }

        async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            embedded_storage::nor_flash::NorFlash::write(&mut self.0.unlocked(), offset, bytes)
        }
    }

    impl embedded_storage_async::nor_flash::MultiwriteNorFlash for ChipFlash {}
}
