//! Runtime glue: exit codes, the panic and HardFault handlers, and the stack meter. The
//! firmware's `unsafe` lives here, in `config` (raw memory the linker names), in `watchdog`
//! (the IWDG's window around an erase), in `chip` and `analog` (register writes the HAL
//! leaves out) and in `qemu` (its stand-ins' `.uninit` RAM and timers).

/// Why the firmware restarted (the core's board reads it at boot), kept across the reset in
/// `.uninit` RAM with a check word (QEMU has no reset flags; on silicon the same record works).
pub use de_resonator::board::ResetCause;

const CAUSE_CHECK: u32 = 0x5E5E_7C0D;

#[link_section = ".uninit.RESET_CAUSE"]
static mut RESET_CAUSE: core::mem::MaybeUninit<[u32; 2]> = core::mem::MaybeUninit::uninit();

/// Record why, then restart the chip.
pub fn reset(cause: ResetCause) -> ! {
    let code = match cause {
        ResetCause::Asked => 1,
        ResetCause::Watchdog => 2,
        ResetCause::BrownOut => 3,
    };
    // SAFETY: a plain store into RAM no one else uses, just before the reset.
    unsafe {
        core::ptr::write_volatile(
            core::ptr::addr_of_mut!(RESET_CAUSE).cast::<[u32; 2]>(),
            [CAUSE_CHECK ^ code, code],
        )
    };
    cortex_m::peripheral::SCB::sys_reset()
}

/// Why the last reset happened: the firmware's own record (`reset`, QEMU's watchdog
/// stand-in), else the chip's reset flags (the IWDG, a brown-out); then forgotten. A power
/// cycle or the reset pin reads `None`.
pub fn take_reset_cause() -> Option<ResetCause> {
    // SAFETY: reads and clears RAM only this module touches; any bit pattern is a valid
    // [u32; 2], and the check word says whether it was written.
    let [check, code] = unsafe {
        let at = core::ptr::addr_of_mut!(RESET_CAUSE).cast::<[u32; 2]>();
        let record = core::ptr::read_volatile(at);
        core::ptr::write_volatile(at, [0, 0]);
        record
    };
    let flags = from_flags();
    if check != CAUSE_CHECK ^ code {
        return flags;
    }
    match code {
        1 => Some(ResetCause::Asked),
        2 => Some(ResetCause::Watchdog),
        3 => Some(ResetCause::BrownOut),
        _ => None,
    }
}

/// End the run with a status (QEMU's exit status under semihosting); on a chip, stop at a
/// breakpoint.
pub fn exit(code: i32) -> ! {
    #[cfg(feature = "qemu")]
    semihosting::process::exit(code);
    #[cfg(not(feature = "qemu"))]
    {
        let _ = code;
        loop {
            cortex_m::asm::bkpt();
        }
    }
}

#[cfg(feature = "defmt")]
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    exit(101)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    #[cfg(feature = "defmt")]
    defmt::error!("panic");
    exit(101)
}

#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    #[cfg(feature = "defmt")]
    defmt::error!(
        "HardFault at pc {=u32:#x}, lr {=u32:#x}",
        frame.pc(),
        frame.lr()
    );
    let _ = frame;
    exit(102)
}

/// The stack's high-water mark, by painting: `paint` fills the free stack below the caller
/// with a pattern (before interrupts are enabled), `used` finds the lowest word that lost it.
pub mod stack {
    use core::ptr::{addr_of, read_volatile, write_volatile};

    const PAINT: u32 = 0xC0DE_CAFE;
    /// Left unpainted below `paint`'s own stack pointer.
    const SLACK_BYTES: u32 = 16;

    extern "C" {
        /// End of the statics, start of the stack's room (cortex-m-rt's link.x).
        static __sheap: u32;
        /// The top of RAM, where the stack starts.
        static _stack_start: u32;
    }

    /// Where the stack starts (only the symbol's address is taken).
    pub fn top() -> u32 {
        addr_of!(_stack_start) as u32
    }

    /// The lowest address the stack may reach (only the symbol's address is taken).
    fn bottom() -> u32 {
        addr_of!(__sheap) as u32
    }

    /// The stack pointer now.
    pub fn pointer() -> u32 {
        cortex_m::register::msp::read()
    }

    /// Paint the free stack from the end of the statics to just below this call's frame.
    /// Call with interrupts off (RTIC's `init`, or a binary that has none).
    #[inline(never)]
    pub fn paint() {
        let sp = pointer();
        let mut at = bottom();
        while at + SLACK_BYTES < sp {
            // SAFETY: [__sheap, sp − slack) is RAM no one uses: below the live stack (no
            // interrupt runs yet), above the statics.
            unsafe { write_volatile(at as *mut u32, PAINT) };
            at += 4;
        }
    }

    /// Bytes of stack used below the address `mark` since `paint` (called with the stack
    /// pointer at or above `mark`).
    pub fn used_below(mark: u32) -> u32 {
        let mut at = bottom();
        // SAFETY: reads of the painted RAM, between the statics and `mark`.
        while at < mark && unsafe { read_volatile(at as *const u32) } == PAINT {
            at += 4;
        }
        mark - at
    }

    /// The deepest the stack has been since `paint`, bytes.
    pub fn used() -> u32 {
        used_below(top())
    }
}

/// The reset the chip's own flags say, when the firmware recorded none (RCC_CSR, then
/// cleared): the IWDG's, or a brown-out (BORRSTF without PORRSTF: a power-on sets both),
/// claimed only where the option bytes turn the brown-out reset on (FLASH_OPTCR's BOR_LEV
/// not 0b11, "off": the chip's default, docs/firmware.md's bring-up sets level 3).
/// Never under QEMU (its RCC reads 0; its watchdog stand-in records its reset in RAM).
fn from_flags() -> Option<ResetCause> {
    #[cfg(not(feature = "qemu"))]
    {
        // SAFETY: RCC_CSR read, then its RMVF bit set to clear the reset flags: no one else
        // touches them.
        let rcc = unsafe { &*stm32f4xx_hal::pac::RCC::ptr() };
        let csr = rcc.csr().read();
        // WDGRSTF: the independent watchdog's (the IWDG's IWDGRSTF in RM0090).
        let cause = if csr.wdgrstf().bit_is_set() {
            Some(ResetCause::Watchdog)
        } else if csr.borrstf().bit_is_set() && csr.porrstf().bit_is_clear() && brown_out_on() {
            Some(ResetCause::BrownOut)
        } else {
            None
        };
        rcc.csr().modify(|_, w| w.rmvf().set_bit());
        cause
    }
    #[cfg(feature = "qemu")]
    None
}

/// Whether the option bytes turn the brown-out reset on (BOR_LEV 0b00, 0b01 or 0b10).
#[cfg(not(feature = "qemu"))]
fn brown_out_on() -> bool {
    // SAFETY: a read of FLASH_OPTCR, which the firmware never writes.
    let flash = unsafe { &*stm32f4xx_hal::pac::FLASH::ptr() };
    flash.optcr().read().bor_lev().bits() != 0b11
}
