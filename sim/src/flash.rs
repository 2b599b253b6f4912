//! The virtual board's flash for the settings store: four 1 KB pages in memory, as
//! memory.x gives the store on the board, so the simulator persists settings, offsets
//! and startup lines through the same core store and the same save rules as the
//! firmware. NOR semantics are kept (programming only clears bits; erase sets a page to
//! 0xFF), and a test can make every write fail.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// The board's flash page size.
pub const PAGE: usize = 1024;
/// The pages the store gets, as on the board.
pub const PAGES: usize = 4;

/// The store's flash region, as offsets into [`RamFlash`].
pub const STORE_RANGE: core::ops::Range<u32> = 0..(PAGE * PAGES) as u32;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlashError {
    OutOfBounds,
    /// Writes were made to fail ([`RamFlash::fail_writes`]).
    WriteFailed,
}

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            FlashError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            FlashError::WriteFailed => NorFlashErrorKind::Other,
        }
    }
}

/// Erased flash in memory.
#[derive(Clone, Debug)]
pub struct RamFlash {
    mem: Vec<u8>,
    /// Every write and erase fails (a worn or protected flash).
    pub fail_writes: bool,
    /// Nanoseconds the CPU has stalled on programming and erasing so far, at the
    /// datasheet's typical figures the emulator uses too (half-word 52.5 µs, page
    /// erase 20 ms): shared with the board, which stops its clock for them.
    pub busy_ns: std::rc::Rc<std::cell::Cell<u64>>,
    /// Page erases so far (each stalls the CPU longer than a service tick).
    pub erases: std::rc::Rc<std::cell::Cell<u64>>,
}

/// Programming one half-word and erasing one page, ns (STM32F103 datasheet, typical).
pub const HALF_WORD_NS: u64 = 52_500;
pub const PAGE_ERASE_NS: u64 = 20_000_000;

impl Default for RamFlash {
    fn default() -> Self {
        RamFlash {
            mem: vec![0xFF; PAGE * PAGES],
            fail_writes: false,
            busy_ns: Default::default(),
            erases: Default::default(),
        }
    }
}

impl RamFlash {
    fn range(&self, offset: u32, len: usize) -> Result<std::ops::Range<usize>, FlashError> {
        let start = offset as usize;
        match start.checked_add(len) {
            Some(end) if end <= self.mem.len() => Ok(start..end),
            _ => Err(FlashError::OutOfBounds),
        }
    }
}

impl ErrorType for RamFlash {
    type Error = FlashError;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.mem[r]);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = PAGE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        let r = self.range(from, to.saturating_sub(from) as usize)?;
        if self.fail_writes {
            return Err(FlashError::WriteFailed);
        }
        let pages = r.len().div_ceil(PAGE) as u64;
        self.mem[r].fill(0xFF);
        self.busy_ns.set(self.busy_ns.get() + pages * PAGE_ERASE_NS);
        self.erases.set(self.erases.get() + pages);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        let r = self.range(offset, bytes.len())?;
        if self.fail_writes {
            return Err(FlashError::WriteFailed);
        }
        for (m, b) in self.mem[r].iter_mut().zip(bytes) {
            *m &= b;
        }
        let half_words = bytes.len().div_ceil(2) as u64;
        self.busy_ns
            .set(self.busy_ns.get() + half_words * HALF_WORD_NS);
        Ok(())
    }
}
