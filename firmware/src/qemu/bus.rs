//! A DAC bus a test can break (QEMU's SPI never fails): from `break_dac_bus` on, every
//! transaction fails, as a broken wire's would on silicon, through resets (a word of
//! `.uninit` RAM, as a broken wire stays broken). Broken by host-sim's link (a scene's
//! failing bus) or by QEMU's `dac-bus-fails` switch.

use embedded_hal::spi::{Error as _, ErrorKind, ErrorType, Operation, SpiDevice};

const BROKEN: u32 = 0xB0_5B_AD_0B;

/// The record: zeros at QEMU's power-up; QEMU's `sys_reset` keeps it.
#[link_section = ".uninit.BUS_BROKEN"]
static mut WORD: core::mem::MaybeUninit<u32> = core::mem::MaybeUninit::uninit();

/// The DAC's bus fails from now on, through resets, until power-up.
pub fn break_dac_bus() {
    // SAFETY: a plain store into RAM only this module touches.
    unsafe { core::ptr::write_volatile(core::ptr::addr_of_mut!(WORD).cast::<u32>(), BROKEN) }
}

/// Whether it is broken.
fn is_broken() -> bool {
    // SAFETY: reads RAM only this module touches; any bit pattern is a valid u32, and only
    // the check word says broken.
    unsafe { core::ptr::read_volatile(core::ptr::addr_of!(WORD).cast::<u32>()) == BROKEN }
}

/// The board's DAC bus, failing once broken.
pub struct Breakable<S>(pub S);

impl<S: SpiDevice> ErrorType for Breakable<S> {
    type Error = ErrorKind;
}

impl<S: SpiDevice> SpiDevice for Breakable<S> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        if is_broken() {
            return Err(ErrorKind::Other);
        }
        self.0.transaction(operations).map_err(|e| e.kind())
    }
}
