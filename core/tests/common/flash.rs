//! A flash for the store's tests: STM32F1-like NOR semantics, and a power cut (or a
//! failing flash) at any write or erase.
#![allow(dead_code)]

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use std::ops::Range;

/// The pages memory.x gives the store on the STM32F103CB (0x0801_F000..0x0802_0000), as
/// flash offsets.
pub const STORE_RANGE: Range<u32> = 0x1_F000..0x2_0000;
pub const PAGE: usize = 1024;
const BASE: u32 = STORE_RANGE.start;
pub const SIZE: usize = (STORE_RANGE.end - STORE_RANGE.start) as usize;

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MockError {
    PowerCut,
    OutOfBounds,
}
impl NorFlashError for MockError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            MockError::PowerCut => NorFlashErrorKind::Other,
            MockError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
        }
    }
}

/// How the operation that the power fails in is left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cut {
    /// Not started.
    Before,
    /// The first half of its bytes done, in address order (the model
    /// log-structured flash stores are usually tested against).
    Prefix,
    /// Writes: half the words done and the next one half-programmed (random bits of
    /// it still 1). Erases: as `Prefix`.
    TornWord,
    /// Erases: every bit of the page in a random state (harsher than the crate's
    /// model). Writes: as `TornWord`.
    RandomErase,
}

/// STM32F1-like flash: 16-bit program unit that must be erased (0xFFFF) before it is
/// programmed, 1 KB pages. Power fails in write/erase number `cut_at`.
pub struct CutFlash {
    pub mem: Vec<u8>,
    pub ops: usize,
    pub cut_at: Option<usize>,
    pub mode: Cut,
    pub dead: bool,
    pub rng: u64,
}

impl CutFlash {
    pub fn new() -> Self {
        CutFlash {
            mem: vec![0xFF; SIZE],
            ops: 0,
            cut_at: None,
            mode: Cut::Before,
            dead: false,
            rng: 0x1234_5678,
        }
    }
    pub fn rand(&mut self) -> u8 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        self.rng as u8
    }
    fn range(&self, offset: u32, len: usize) -> Result<std::ops::Range<usize>, MockError> {
        let start = offset.checked_sub(BASE).ok_or(MockError::OutOfBounds)? as usize;
        if start + len > SIZE {
            return Err(MockError::OutOfBounds);
        }
        Ok(start..start + len)
    }
    /// True if this operation is the one the power fails on.
    fn cut_now(&mut self) -> Result<bool, MockError> {
        if self.dead {
            return Err(MockError::PowerCut);
        }
        let op = self.ops;
        self.ops += 1;
        Ok(self.cut_at == Some(op))
    }
    /// Power back on.
    pub fn reboot(&mut self) {
        self.dead = false;
        self.cut_at = None;
    }
}

impl ErrorType for CutFlash {
    type Error = MockError;
}
impl ReadNorFlash for CutFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), MockError> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.mem[r]);
        Ok(())
    }
    fn capacity(&self) -> usize {
        SIZE
    }
}
impl NorFlash for CutFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = PAGE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), MockError> {
        let r = self.range(from, (to - from) as usize)?;
        assert!(r.start % PAGE == 0 && r.end % PAGE == 0, "unaligned erase");
        if self.cut_now()? {
            match self.mode {
                Cut::Before => {}
                Cut::Prefix | Cut::TornWord => self.mem[r.start..r.start + PAGE / 2].fill(0xFF),
                Cut::RandomErase => {
                    for i in r {
                        self.mem[i] |= self.rand();
                    }
                }
            }
            self.dead = true;
            return Err(MockError::PowerCut);
        }
        self.mem[r].fill(0xFF);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), MockError> {
        let r = self.range(offset, bytes.len())?;
        assert!(
            r.start.is_multiple_of(2) && bytes.len().is_multiple_of(2),
            "unaligned write"
        );
        for (w, i) in bytes.chunks(2).zip(r.clone().step_by(2)) {
            let old = [self.mem[i], self.mem[i + 1]];
            assert!(
                old == [0xFF, 0xFF] || w == [0, 0],
                "programming a word that is not erased at {i:#x}"
            );
        }
        let cut = self.cut_now()?;
        let words = bytes.len() / 2;
        let done = match (cut, self.mode) {
            (false, _) => words,
            (true, Cut::Before) => 0,
            (true, _) => words / 2,
        };
        for k in 0..done {
            self.mem[r.start + 2 * k] = bytes[2 * k];
            self.mem[r.start + 2 * k + 1] = bytes[2 * k + 1];
        }
        if cut {
            if self.mode == Cut::Prefix && !bytes.len().is_multiple_of(4) && words > 0 {
                // Byte order: the odd byte of the middle word lands too.
                self.mem[r.start + 2 * done] = bytes[2 * done];
            } else if matches!(self.mode, Cut::TornWord | Cut::RandomErase) && done < words {
                // Half-programmed word: some of its 0 bits did not make it.
                for b in 0..2 {
                    let i = r.start + 2 * done + b;
                    self.mem[i] = bytes[2 * done + b] | self.rand();
                }
            }
            self.dead = true;
            return Err(MockError::PowerCut);
        }
        Ok(())
    }
}
