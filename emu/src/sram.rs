//! The chip's SRAM, one buffer seen by two bus masters: the CPU (unicorn maps it as
//! its RAM) and the DMA controller (the board reads and writes it while a transfer
//! lands, between two blocks of the CPU). Shaped as a raw allocation because unicorn
//! writes it from C: nothing here ever holds a Rust reference into it, every access
//! is a raw read or write of a few bytes.

use std::ffi::c_void;

pub struct Sram {
    ptr: *mut u8,
    len: usize,
}

impl Sram {
    /// `len` bytes of zeroed memory.
    pub fn new(len: usize) -> Sram {
        let b = vec![0u8; len].into_boxed_slice();
        Sram {
            ptr: Box::into_raw(b).cast::<u8>(),
            len,
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The address unicorn maps (`mem_map_ptr`); valid as long as this value lives.
    pub fn as_ptr(&self) -> *mut c_void {
        self.ptr.cast()
    }

    /// `size` bytes (1, 2 or 4) at offset `off`, little-endian; None outside.
    pub fn read(&self, off: usize, size: usize) -> Option<u32> {
        if off.checked_add(size)? > self.len {
            return None;
        }
        let mut v = 0u32;
        for i in 0..size {
            // SAFETY: off + i < len (checked above), inside the allocation; the CPU is
            // not running (single thread), so nothing writes it meanwhile.
            let b = unsafe { self.ptr.add(off + i).read() };
            v |= u32::from(b) << (8 * i);
        }
        Some(v)
    }

    /// Write the low `size` bytes of `v` at offset `off`; None (nothing written) outside.
    pub fn write(&mut self, off: usize, size: usize, v: u32) -> Option<()> {
        if off.checked_add(size)? > self.len {
            return None;
        }
        for i in 0..size {
            // SAFETY: as in `read`; `&mut self` orders this after every other access
            // from this side, and the CPU is not running.
            unsafe { self.ptr.add(off + i).write((v >> (8 * i)) as u8) };
        }
        Some(())
    }
}

impl Drop for Sram {
    fn drop(&mut self) {
        // SAFETY: `ptr` and `len` came from `Box::into_raw` of a boxed slice of `len`
        // bytes in `new`, freed only here. Unicorn, which maps it, is closed first
        // (the board that owns this lives in unicorn's data, dropped after uc_close).
        drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(self.ptr, self.len)) });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn little_endian_words_inside_and_nothing_outside() {
        let mut m = Sram::new(8);
        assert_eq!(m.write(2, 4, 0x1122_3344), Some(()));
        assert_eq!(m.read(2, 1), Some(0x44));
        assert_eq!(m.read(4, 2), Some(0x1122));
        assert_eq!(m.read(0, 4), Some(0x3344_0000));
        assert_eq!(m.read(6, 4), None);
        assert_eq!(m.write(7, 2, 0xFFFF), None);
        assert_eq!(m.read(7, 1), Some(0));
    }
}
