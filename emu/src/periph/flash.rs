//! The embedded flash: its array and its controller FPEC (RM0008 section 3.3.3 and the
//! STM32F10xxx flash programming manual PM0075): unlock with the two keys, half-word
//! programming with PG, page erase with PER/AR/STRT, mass erase with MER, BSY, EOP,
//! PGERR and WRPRTERR, ACR wait states.
//!
//! The array can live in a file that is written through at every program and erase
//! operation, so a run that stops at any moment (a power cut) leaves the file exactly
//! as the flash would be, and the next run starts from it. A power cut is modelled at
//! a given operation: that operation and everything after it never happen.
//!
//! Timings (STM32F103xB datasheet, table "Flash memory characteristics", typical):
//! half-word program 52.5 µs, page erase 20 ms, mass erase 20 ms. The CPU fetches its
//! instructions from this flash, so it stalls for the whole operation (PM0075 2.3.3):
//! the machine adds the time to the clock.

use super::{unknown, Access, BusError};
use crate::clock::T_PER_US;
use std::fs::File;
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::path::Path;

pub const BASE: u32 = 0x0800_0000;
pub const SIZE: usize = 128 * 1024;
pub const PAGE: usize = 1024;
const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;
pub const PROGRAM_T: u64 = 52 * T_PER_US + T_PER_US / 2;
pub const ERASE_T: u64 = 20_000 * T_PER_US;

/// What a write to the array did.
pub enum Op {
    /// Nothing changed in the array (an error flag may have been raised).
    None,
    /// `BASE + at .. + len` changed; the CPU stalls for `stall_t`.
    Changed { at: usize, len: usize, stall_t: u64 },
    /// The power was cut at this operation: the run stops here.
    PowerCut,
}

pub struct Flash {
    pub array: Vec<u8>,
    file: Option<File>,
    acr: u32,
    sr: u32,
    cr: u32,
    ar: u32,
    /// 0: locked, 1: first key seen, 2: unlocked; a wrong key locks until reset.
    key_state: u8,
    key_locked_out: bool,
    /// Program and erase operations so far (the power-cut counter).
    pub ops: usize,
    /// Cut the power at this operation (0-based).
    pub cut_at: Option<usize>,
}

impl Flash {
    /// A blank (erased) array, kept in `file` if given: an existing file is the array
    /// as the last run left it.
    pub fn new(file: Option<&Path>) -> std::io::Result<Flash> {
        let mut array = vec![0xFF; SIZE];
        let file = match file {
            Some(p) => {
                let mut f = std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(false)
                    .open(p)?;
                let len = f.metadata()?.len() as usize;
                if len == SIZE {
                    f.read_exact_at(&mut array, 0)?;
                } else {
                    f.set_len(0)?;
                    f.write_all(&array)?;
                }
                Some(f)
            }
            None => None,
        };
        Ok(Flash {
            array,
            file,
            acr: 0x30,
            sr: 0,
            cr: 0x80,
            ar: 0,
            key_state: 0,
            key_locked_out: false,
            ops: 0,
            cut_at: None,
        })
    }

    /// Load a program's segments as a probe flashes it: every page they cover is
    /// erased first, then written; the rest of the array keeps its contents (the
    /// settings pages survive a reflash).
    pub fn load(&mut self, segments: &[(u32, &[u8])]) -> Result<(), String> {
        let mut ranges = Vec::new();
        for &(addr, bytes) in segments {
            let at = addr.checked_sub(BASE).ok_or("below flash")? as usize;
            let end = at + bytes.len();
            if end > SIZE {
                return Err(format!(
                    "segment at 0x{addr:08X} is outside the 128 KB flash"
                ));
            }
            ranges.push((at, end));
        }
        for &(at, end) in &ranges {
            let (first, last) = (at / PAGE * PAGE, end.div_ceil(PAGE) * PAGE);
            self.array[first..last].fill(0xFF);
        }
        for (&(at, end), &(_, bytes)) in ranges.iter().zip(segments) {
            self.array[at..end].copy_from_slice(bytes);
        }
        for &(at, end) in &ranges {
            let (first, last) = (at / PAGE * PAGE, end.div_ceil(PAGE) * PAGE);
            self.persist(first, last - first);
        }
        Ok(())
    }

    fn persist(&mut self, at: usize, len: usize) {
        if let Some(f) = &self.file {
            // The run goes on if the file cannot be written; the next start says so.
            let _ = f.write_all_at(&self.array[at..at + len], at as u64);
        }
    }

    /// ACR latency: wait states for reads at the current clock.
    pub fn latency(&self) -> u32 {
        self.acr & 7
    }

    pub fn read_reg(&self, off: u32) -> Access<u32> {
        Ok(match off {
            // PRFTBS follows PRFTBE.
            0x00 => (self.acr & 0x1F) | ((self.acr & 0x10) << 1),
            0x04 | 0x08 => 0,
            0x0C => self.sr,
            0x10 => self.cr,
            0x14 => self.ar,
            // OBR: no read protection, option bytes at their defaults; WRPR: none.
            0x1C => 0x03FF_FFFC,
            0x20 => 0xFFFF_FFFF,
            _ => return Err(unknown("FLASH", off)),
        })
    }

    pub fn write_reg(&mut self, off: u32, v: u32) -> Access<Op> {
        match off {
            0x00 => self.acr = v & 0x1F,
            0x04 => {
                self.key_state = match (self.key_state, v) {
                    _ if self.key_locked_out => 0,
                    (0, KEY1) => 1,
                    (1, KEY2) => {
                        self.cr &= !0x80;
                        2
                    }
                    (2, _) => 2,
                    _ => {
                        // A wrong sequence locks the FPEC until the next reset and
                        // answers with a bus error (PM0075 2.3.1).
                        self.key_locked_out = true;
                        return Err(BusError("FLASH_KEYR: wrong key sequence".into()));
                    }
                };
            }
            0x08 => {}
            0x0C => {
                // PGERR, WRPRTERR, EOP are cleared by writing 1.
                self.sr &= !(v & 0x34);
            }
            0x10 => {
                if self.cr & 0x80 != 0 {
                    // Locked: CR cannot be written (only LOCK stays set).
                    return Ok(Op::None);
                }
                self.cr = v & 0x16F7;
                if v & 0x80 != 0 {
                    self.key_state = 0;
                }
                if v & (1 << 6) != 0 {
                    return Ok(self.start());
                }
            }
            0x14 => {
                if self.sr & 1 == 0 {
                    self.ar = v;
                }
            }
            _ => return Err(unknown("FLASH", off)),
        }
        Ok(Op::None)
    }

    /// STRT: a page or mass erase.
    fn start(&mut self) -> Op {
        self.cr &= !(1 << 6);
        let (at, len) = if self.cr & 4 != 0 {
            (0, SIZE)
        } else if self.cr & 2 != 0 {
            let Some(a) = self.ar.checked_sub(BASE).filter(|&a| (a as usize) < SIZE) else {
                // An address outside the array erases nothing.
                return Op::None;
            };
            (a as usize / PAGE * PAGE, PAGE)
        } else {
            return Op::None;
        };
        if self.cut() {
            return Op::PowerCut;
        }
        self.array[at..at + len].fill(0xFF);
        self.persist(at, len);
        self.sr |= 1 << 5;
        Op::Changed {
            at,
            len,
            stall_t: ERASE_T,
        }
    }

    fn cut(&mut self) -> bool {
        let n = self.ops;
        self.ops += 1;
        self.cut_at == Some(n)
    }

    /// A CPU write into the array at `offset`. With PG set a half-word is programmed
    /// (only over an erased half-word, or to 0x0000; otherwise PGERR); anything else
    /// is a bus error.
    pub fn write_array(&mut self, offset: usize, size: usize, v: u32) -> Access<Op> {
        if self.cr & 1 == 0 || self.cr & 0x80 != 0 {
            return Err(BusError(format!(
                "flash write at 0x{:08X} without PG set and the flash unlocked",
                BASE as usize + offset
            )));
        }
        if size != 2 || !offset.is_multiple_of(2) {
            return Err(BusError(format!(
                "flash programming takes half-words only ({size}-byte write at 0x{:08X})",
                BASE as usize + offset
            )));
        }
        let old = u16::from_le_bytes([self.array[offset], self.array[offset + 1]]);
        let new = v as u16;
        if old != 0xFFFF && new != 0 {
            self.sr |= 1 << 2;
            return Ok(Op::None);
        }
        if self.cut() {
            return Ok(Op::PowerCut);
        }
        self.array[offset..offset + 2].copy_from_slice(&new.to_le_bytes());
        self.persist(offset, 2);
        self.sr |= 1 << 5;
        Ok(Op::Changed {
            at: offset,
            len: 2,
            stall_t: PROGRAM_T,
        })
    }

    pub fn read_array(&self, offset: usize, size: usize) -> u32 {
        let mut v = 0;
        for i in 0..size {
            v |= u32::from(self.array.get(offset + i).copied().unwrap_or(0xFF)) << (8 * i);
        }
        v
    }

    /// A system reset: the controller's registers reset, the array stays.
    pub fn reset(&mut self) {
        self.acr = 0x30;
        self.sr = 0;
        self.cr = 0x80;
        self.ar = 0;
        self.key_state = 0;
        self.key_locked_out = false;
    }
}
