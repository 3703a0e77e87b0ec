//! The flash layer every record kept in flash sits on (the settings' two slots, `store`; the
//! fault log's two halves, `fault_log`): a range as two halves of whole pages, how a flash
//! operation failed, and a NOR flash in RAM for QEMU and the tests (which can fail or tear a
//! write at any byte: a power cut). Over embedded-storage's blocking `NorFlash`: the chip's
//! flash controller waits in each call, so an async store was only ever blocked on, and its
//! futures cost stack and flash (BENCHMARKS.md, "Target: flash and RAM").

use core::ops::Range;

use embedded_storage::nor_flash::{
    ErrorType, MultiwriteNorFlash, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// How a flash operation failed (embedded-storage's kinds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FlashKind {
    NotAligned,
    OutOfBounds,
    Other,
}

impl From<NorFlashErrorKind> for FlashKind {
    fn from(kind: NorFlashErrorKind) -> Self {
        match kind {
            NorFlashErrorKind::NotAligned => FlashKind::NotAligned,
            NorFlashErrorKind::OutOfBounds => FlashKind::OutOfBounds,
            _ => FlashKind::Other,
        }
    }
}

/// `range` as two halves of whole flash pages: their starts and their length in bytes (the
/// settings' two slots; the fault log's two halves); `None` if it is not.
pub fn halves<F: NorFlash>(range: &Range<u32>) -> Option<([u32; 2], usize)> {
    let len = range.end.checked_sub(range.start)? as usize;
    let half = len / 2;
    let page = F::ERASE_SIZE.max(1);
    let whole = len.is_multiple_of(2)
        && half.is_multiple_of(page)
        && (range.start as usize).is_multiple_of(page);
    whole.then_some(([range.start, range.start + half as u32], half))
}

/// A NOR flash in RAM: erased bytes read 0xFF, a write can only clear bits, writes are whole
/// `WORD`-byte words and erases whole pages (else `NotAligned`, as real flash refuses). For
/// QEMU (whose flash controller is not emulated) and tests: `fail_after` bytes written from
/// now, the next write or erase fails there, having done the bytes before it (a torn write:
/// a power cut).
pub struct RamFlashWords<'a, const WORD: usize> {
    bytes: &'a mut [u8],
    /// Bytes a write or erase may still change before it fails (`None`: never).
    pub fail_after: Option<usize>,
}

/// The RAM flash of 4-byte words the firmware's QEMU build uses.
pub type RamFlash<'a> = RamFlashWords<'a, RAM_WORD_BYTES>;

/// Page and word of `RamFlash`.
pub const RAM_PAGE_BYTES: usize = 1024;
pub const RAM_WORD_BYTES: usize = 4;

/// A `RamFlash` write or erase that failed (on purpose, or out of range).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RamFlashError(NorFlashErrorKind);

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

impl<'a, const WORD: usize> RamFlashWords<'a, WORD> {
    /// Over `bytes` as they are (a whole number of pages; erased or not).
    pub fn new(bytes: &'a mut [u8]) -> Self {
        Self {
            bytes,
            fail_after: None,
        }
    }

    /// The bytes, for a test that looks at them or corrupts them.
    pub fn bytes(&mut self) -> &mut [u8] {
        self.bytes
    }

    /// One byte changed by a write or erase, unless the budget is spent.
    fn spend(&mut self) -> Result<(), RamFlashError> {
        match self.fail_after {
            Some(0) => Err(RamFlashError(NorFlashErrorKind::Other)),
            Some(n) => {
                self.fail_after = Some(n - 1);
                Ok(())
            }
            None => Ok(()),
        }
    }

    fn span(&mut self, offset: u32, len: usize) -> Result<&mut [u8], RamFlashError> {
        let from = offset as usize;
        self.bytes
            .get_mut(from..from.saturating_add(len))
            .ok_or(RamFlashError(NorFlashErrorKind::OutOfBounds))
    }
}

impl<const WORD: usize> ErrorType for RamFlashWords<'_, WORD> {
    type Error = RamFlashError;
}

impl<const WORD: usize> ReadNorFlash for RamFlashWords<'_, WORD> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, out: &mut [u8]) -> Result<(), Self::Error> {
        let span = self.span(offset, out.len())?;
        out.copy_from_slice(span);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl<const WORD: usize> NorFlash for RamFlashWords<'_, WORD> {
    const WRITE_SIZE: usize = WORD;
    const ERASE_SIZE: usize = RAM_PAGE_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = (to as usize).saturating_sub(from as usize);
        let page = RAM_PAGE_BYTES;
        if !((from as usize).is_multiple_of(page) && len.is_multiple_of(page)) {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        self.span(from, len)?;
        for at in from as usize..to as usize {
            self.spend()?;
            if let Some(b) = self.bytes.get_mut(at) {
                *b = 0xFF;
            }
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), Self::Error> {
        let word = WORD.max(1);
        if !((offset as usize).is_multiple_of(word) && data.len().is_multiple_of(word)) {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        self.span(offset, data.len())?;
        for (k, &byte) in data.iter().enumerate() {
            self.spend()?;
            if let Some(b) = self.bytes.get_mut(offset as usize + k) {
                *b &= byte;
            }
        }
        Ok(())
    }
}

impl<const WORD: usize> MultiwriteNorFlash for RamFlashWords<'_, WORD> {}
